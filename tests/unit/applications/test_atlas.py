"""The error atlas design: the map from the unit cube to physical points keeps the groups it promises."""

import math

import numpy as np
import pytest

from screening.applications import atlas


@pytest.fixture(scope="module")
def groups():
    return atlas.groups_of(atlas.design(256, seed=3))


def test_design_is_stratified_and_reproducible():
    u = atlas.design(1024, seed=0)
    assert u.shape == (1024, len(atlas.GROUPS))
    assert np.array_equal(u, atlas.design(1024, seed=0))
    # a scrambled Sobol net: every coordinate puts exactly 1024/32 points in each of 32 equal bins
    for j in range(u.shape[1]):
        assert np.all(np.bincount((u[:, j] * 32).astype(int), minlength=32) == 32)


@pytest.mark.parametrize("bad", [0, -3, 2.5, True])
def test_design_rejects_bad_size(bad):
    with pytest.raises(ValueError, match="n_points"):
        atlas.design(bad)


def test_groups_within_ranges(groups):
    lo, hi = atlas.RANGES["alpha"]
    assert np.all((groups["alpha"] >= lo) & (groups["alpha"] <= hi))
    assert np.all((groups["r_ul"] >= 3e-5 * (1 - 1e-12)) & (groups["r_ul"] <= 0.25 * (1 + 1e-12)))
    soft = groups["bed_law"] == "softening"
    hard = groups["bed_law"] == "hardening"
    assert np.all(groups["e"][soft] < 0) and np.all(groups["e"][hard] > 0)
    assert np.all(groups["e"][~soft & ~hard] == 0)
    white = groups["kind"] == "white"
    assert np.all(np.isnan(groups["omega_g_p"][white])) and np.all(np.isfinite(groups["omega_g_p"][~white]))
    beyond = groups["factor"] > 1
    assert np.all(groups["p_target"][beyond] == atlas.P_BEYOND)
    assert np.all((groups["p_target"] >= atlas.P_TARGET[0] - 1e-12) & (groups["p_target"] <= atlas.P_TARGET[1] + 1e-12))


def test_intensity_axis_is_monotone():
    u = np.full((50, len(atlas.GROUPS)), 0.5)
    u[:, atlas.GROUPS.index("u_intensity")] = np.linspace(0, atlas.BEYOND_EDGE - 1e-9, 50)
    p = atlas.groups_of(u)["p_target"]
    assert np.all(np.diff(p) > 0)
    assert p[0] == pytest.approx(atlas.P_TARGET[0], rel=1e-9) and p[-1] == pytest.approx(atlas.P_TARGET[1], rel=1e-6)


def test_physical_point_round_trips_the_groups(groups):
    for i in range(0, 256, 7):
        block, foundation, shape, timing = atlas.physical_point(groups, i)
        got = atlas.measured_groups(block, foundation, shape, timing)
        for name in ("alpha", "r_ul", "zeta_v", "e", "tau"):
            assert got[name] == pytest.approx(groups[name][i], rel=1e-9, abs=1e-15), name
        if shape["kind"] == "kanai_tajimi":
            assert got["omega_g_p"] == pytest.approx(groups["omega_g_p"][i], rel=1e-12)
            assert shape["zeta_g"] == groups["zeta_g"][i]
        assert got["record_T1"] == pytest.approx(atlas.RECORD_T1)
        assert timing["T2"] == pytest.approx(timing["T1"] / 2)


def test_housner_frequency_against_the_rigid_block_pendulum():
    # small free oscillation about a corner of a rigid block hanging below it: omega^2 = m g R / I_O
    from screening.core.model import Block

    blk = Block(m=7.0, b=0.3, h=1.1)
    R = math.hypot(0.3, 1.1)
    I_O = 7.0 * (0.3**2 + 1.1**2) / 3 + 7.0 * 1.1**2 + 7.0 * 0.3**2      # parallel axes about the corner
    assert atlas.housner_frequency(blk) == pytest.approx(math.sqrt(7.0 * 9.81 * R / I_O), rel=1e-12)
    assert atlas.housner_frequency(blk) == pytest.approx(math.sqrt(3 * 9.81 / (4 * R)), rel=1e-12)


def test_derived_frequency_ratios_follow_from_alpha_and_r_ul(groups):
    for i in range(0, 256, 11):
        block, foundation, shape, _ = atlas.physical_point(groups, i)
        d = atlas.derived_groups(block, foundation, shape, 1e-3)
        a, th = groups["alpha"][i], groups["r_ul"][i] * groups["alpha"][i]
        # the bed's rocking mode turns about the base centre: inertia I_cm + m h^2, not I_O = 4 m R^2 / 3
        inertia = (4 / 3) / (1 / 3 + math.cos(a) ** 2)
        assert d["w_r_p"] ** 2 == pytest.approx((math.sin(a) / (3 * th) - math.cos(a)) * inertia, rel=1e-9)
        assert d["w_v_p"] ** 2 == pytest.approx(4 / (3 * math.sin(a) * th), rel=1e-9)


def test_families_partition_the_design(groups):
    fam = atlas.family_of(groups)
    for f in np.unique(fam):
        members = fam == f
        name = atlas.family_name(f)
        assert len(set(groups["kind"][members])) == 1 and name.endswith(groups["kind"][members][0])
        assert len(set(groups["bed_law"][members])) == 1 and groups["bed_law"][members][0] in name
        a_bin = np.digitize(groups["alpha"][members], atlas.FAMILY_ALPHA_EDGES)
        assert len(set(a_bin)) == 1 and name.startswith(f"alpha{a_bin[0]}-")
