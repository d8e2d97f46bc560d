"""The per-point trust rule (screening.analysis.trust): synthetic indicators, held-out calibration, shipped file."""

import json

import numpy as np
import pytest

from screening import Block, Foundation, WhiteNoise, linearize
from screening.analysis import trust
from screening.core.status import PointStatus, Trust


def rows(p, err, se=None, cond="paper", law="hardening", over=0.0, decay=1.0, sigma=0.01, margin=0.9):
    p = np.asarray(p, dtype=float)
    n = p.size

    def full(x):
        return np.broadcast_to(np.asarray(x), (n,)).copy()

    return {"peak_p_uplift": p, "k_eq_margin": full(float(margin)), "sigma_ratio": full(float(sigma)),
            "decay_excess": full(float(decay)), "error": np.asarray(err, dtype=float),
            "error_se": full(0.02 if se is None else se), "overturned_fraction": full(float(over)),
            "condensation": full(cond).astype(str), "bed_law": full(law).astype(str),
            "point": np.array([f"pt{i}" for i in range(n)])}


def concat(*parts):
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}


SYNTHETIC = concat(
    rows([0.001, 0.003, 0.02, 0.05], [-0.03, -0.05, -0.06, -0.08], law="softening"),
    rows([0.15, 0.3], [-0.2, -0.35], law="softening"),
    rows([0.001, 0.003], [-0.15, -0.14], law="hardening"),
    rows([0.002, 0.004, 0.03, 0.05], [0.02, -0.04, 0.05, -0.03], law="linear"),
    rows([0.5, 0.95], [-0.02, 0.01], law="linear"),             # trusted data at high uplift: must not raise trust
    rows([0.99], [1.5], law="linear", decay=500.0),             # lock-in
)


def ind(p, decay=1.0, sigma=0.01, margin=0.9):
    return {"peak_p_uplift": np.asarray(p, dtype=float), "k_eq_margin": np.full(np.shape(p), margin),
            "sigma_ratio": np.full(np.shape(p), sigma), "decay_excess": np.full(np.shape(p), decay)}


@pytest.fixture(scope="module")
def table():
    return trust.trust_table(None, rows=SYNTHETIC)


def test_trusted_only_where_the_cell_errors_are_within_10_percent(table):
    flag, lo, hi = trust.sl_trust(ind([0.001, 0.03]), table, eps=-6e5)
    assert list(flag) == [Trust.trusted, Trust.trusted]
    assert lo[0] == pytest.approx(-0.05 - 0.04) and hi[0] == pytest.approx(-0.03 + 0.04)
    flag, _, _ = trust.sl_trust(ind([0.001]), table, eps=6e7)     # -15 % on the hardening bed
    assert flag[0] == Trust.check
    flag, _, _ = trust.sl_trust(ind([0.15]), table, eps=-6e5)
    assert flag[0] == Trust.check                               # -20 %: check, not trusted
    flag, _, _ = trust.sl_trust(ind([0.3]), table, eps=-6e5)
    assert flag[0] == Trust.check


@pytest.mark.parametrize("eps", [6e7, 0.0, -6e5])
@pytest.mark.parametrize("cond", ["paper", "cubic"])
def test_more_uplift_never_raises_trust(table, eps, cond):
    p = np.linspace(0.0, 1.0, 501)
    flag, _, _ = trust.sl_trust(ind(p), table, eps=eps, condensation=cond)
    assert np.all(np.diff(flag.astype(int)) >= 0)


def test_linear_high_uplift_stays_below_the_worst_lower_cell(table):
    # the linear bed's 0.5 and 0.95 cells have good data, but the empty 0.08-0.45 bins are 'check'
    flag, _, _ = trust.sl_trust(ind([0.003, 0.5, 0.95]), table, eps=0.0)
    assert list(flag) == [Trust.trusted, Trust.check, Trust.check]


def test_lock_in_is_untrusted(table):
    flag, lo, hi = trust.sl_trust(ind([0.003, 0.003], decay=[1.0, 1e3]), table, eps=0.0)
    assert flag[0] == Trust.trusted and flag[1] == Trust.untrusted
    assert lo[1] == pytest.approx(1.5 - 0.04) and hi[1] == pytest.approx(1.5 + 0.04)


@pytest.mark.parametrize("kw", [dict(sigma=0.5), dict(margin=0.1)])
def test_near_toppling_is_untrusted(table, kw):
    flag, _, _ = trust.sl_trust(ind([0.003], **kw), table, eps=0.0)
    assert flag[0] == Trust.untrusted


@pytest.mark.parametrize("status", [s for s in PointStatus if s != PointStatus.ok])
def test_non_ok_status_is_untrusted_without_band(table, status):
    flag, lo, hi = trust.sl_trust(ind([0.003, 0.003]), table, status=[int(status), 0], eps=0.0)
    assert flag[0] == Trust.untrusted and np.isnan(lo[0]) and np.isnan(hi[0])
    assert flag[1] == Trust.trusted


def test_overturning_in_the_calibration_makes_the_cell_untrusted():
    t = trust.trust_table(None, rows=rows([0.001, 0.002], [0.01, 0.02], over=0.05, law="linear"))
    flag, _, _ = trust.sl_trust(ind([0.001]), t, eps=0.0)
    assert flag[0] == Trust.untrusted


def test_an_uncalibrated_condensation_is_at_best_check_and_has_no_band(table):
    """Bands measured on the paper's and the cubic condensation do not describe another one
    (virtual_work measured -2 % where the pooled band said [-100 %, -12 %])."""
    flag, lo, hi = trust.sl_trust(ind([0.003, 0.9]), table, eps=0.0, condensation="virtual_work")
    assert flag[0] == Trust.check and (flag != Trust.trusted).all() and np.isnan(lo).all() and np.isnan(hi).all()
    known, klo, _ = trust.sl_trust(ind([0.003]), table, eps=0.0, condensation="paper")
    assert np.isfinite(klo[0])


# ----------------------------------------------------------------------------- the shipped calibration
@pytest.fixture(scope="module")
def calibration():
    try:
        return trust.shipped_calibration()
    except (FileNotFoundError, OSError):
        pytest.skip("no shipped calibration file")


def test_shipped_table_is_the_one_derived_from_the_shipped_file(calibration):
    assert trust.trust_table(calibration) == json.loads(calibration.attrs["trust_table"])
    assert calibration.sizes["point"] >= 30


def test_shipped_trusted_cells_are_earned(calibration):
    """Every calibration row the shipped rule labels trusted is within 10 % (and its band within 25 %)."""
    r = trust.calibration_rows(calibration)
    flag, lo, hi = trust.sl_trust(r, None, condensation=r["condensation"], eps=np.where(
        r["bed_law"] == "hardening", 1.0, np.where(r["bed_law"] == "softening", -1.0, 0.0)))
    t = flag == Trust.trusted
    assert np.all(np.abs(r["error"][t]) <= trust.TRUSTED_ERROR)
    assert np.all((lo[t] >= -trust.TRUSTED_BAND) & (hi[t] <= trust.TRUSTED_BAND))


def _subset(r, keep):
    return {k: v[keep] for k, v in r.items()}


def _eps(r):
    return np.where(r["bed_law"] == "hardening", 1.0, np.where(r["bed_law"] == "softening", -1.0, 0.0))


def _held_out(r, train, label):
    """Derive the cells from the rows ``train``, label the others; no held-out row beyond 25 % may be trusted."""
    table = trust.trust_table(None, rows=_subset(r, train))
    test = _subset(r, ~train)
    flag, _, _ = trust.sl_trust(test, table, condensation=test["condensation"], eps=_eps(test))
    trusted = flag == Trust.trusted
    beyond_10 = int(np.sum(trusted & (np.abs(test["error"]) > trust.TRUSTED_ERROR)))
    print(f"held-out {label}: {int(trusted.sum())} of {trusted.size} rows trusted, {beyond_10} of them beyond 10 %")
    assert not np.any(trusted & (np.abs(test["error"]) > trust.TRUSTED_BAND)), \
        f"held-out rows beyond 25 % labelled trusted: {test['point'][trusted & (np.abs(test['error']) > 0.25)]}"
    return int(trusted.sum()), beyond_10


@pytest.mark.parametrize("part", [0, 1])
def test_held_out_every_other_point(calibration, part):
    r = trust.calibration_rows(calibration)
    names = sorted(set(r["point"].tolist()))
    _held_out(r, np.isin(r["point"], names[part::2]), f"every other point, part {part}")


@pytest.mark.parametrize("kind", ["white", "kanai_tajimi"])
def test_held_out_by_excitation_kind(calibration, kind):
    r = trust.calibration_rows(calibration)
    kinds = dict(zip(calibration.point.values.tolist(), calibration.excitation_kind.values.tolist()))
    train = np.array([kinds[p] != kind for p in r["point"]])
    _held_out(r, train, f"{kind} held out")


def test_held_out_leave_one_point_out(calibration):
    r = trust.calibration_rows(calibration)
    total = beyond = 0
    for name in sorted(set(r["point"].tolist())):
        n, b = _held_out(r, r["point"] != name, name)
        total, beyond = total + n, beyond + b
    print(f"leave-one-point-out: {total} rows trusted, {beyond} beyond 10 %")


# ----------------------------------------------------------------------------- add_cell_trust
def test_add_cell_trust_on_a_linearize_result():
    ds = linearize(Block(8.67, 0.035, 0.21), Foundation(k=2.89e7, lam=8.95e8, eps=np.array([-6e5, 0.0, 6e7])),
                   WhiteNoise(np.array([1e-7, 1e-5, 1e-2])))
    table = trust.trust_table(None, rows=SYNTHETIC)
    out = trust.add_cell_trust(ds, table)
    for name in ("sl_trust", "sl_error_low", "sl_error_high"):
        assert out[name].dims == ds.peak_var_theta.dims
    assert out.sl_trust.attrs["flag_meanings"] == "trusted check untrusted"
    assert list(out.sl_trust.attrs["flag_values"]) == [0, 1, 2]
    assert out.sl_error_low.attrs["units"] == "1"
    flag = out.sl_trust.values
    assert np.all(flag[ds.status.values != 0] == Trust.untrusted)
    # more intensity never raises trust on one bed
    assert np.all(np.diff(flag.astype(int), axis=1) >= 0)


def test_add_cell_trust_on_a_single_point():
    ds = linearize(Block(8.67, 0.035, 0.21), Foundation(k=2.89e7, lam=8.95e8, eps=-6e5), WhiteNoise(1e-7))
    out = trust.add_cell_trust(ds, trust.trust_table(None, rows=SYNTHETIC))
    assert out.sl_trust.ndim == 0 and int(out.sl_trust) in (0, 1, 2)


def test_missing_indicators_never_trusted(table):
    flag, _, _ = trust.sl_trust(ind([0.003, 0.003], decay=[1.0, np.nan]), table, eps=0.0)
    assert list(flag) == [Trust.trusted, Trust.check]


def test_add_cell_trust_without_histories_is_never_trusted():
    ds = linearize(Block(8.67, 0.035, 0.21), Foundation(k=2.89e7, lam=8.95e8, eps=-6e5), WhiteNoise(np.array([1e-7, 1e-6])))
    table = trust.trust_table(None, rows=SYNTHETIC)
    full = trust.add_cell_trust(ds, table)
    bare = trust.add_cell_trust(ds.drop_vars(["var_theta", "k_eq"]), table)
    assert np.all(bare.sl_trust.values >= full.sl_trust.values)
    assert not np.any(bare.sl_trust.values == Trust.trusted)
    with_summaries = ds.drop_vars(["var_theta", "k_eq"]).assign(k_eq_rest=ds.k_eq.isel(t=0),
                                                                 var_theta_end=ds.var_theta.isel(t=-1))
    np.testing.assert_array_equal(trust.add_cell_trust(with_summaries, table).sl_trust.values, full.sl_trust.values)


def test_shipped_rule_is_monotone_in_uplift(calibration):
    p = np.linspace(0.0, 1.0, 1001)
    for cond in trust.CONDENSATIONS:
        for eps in (6e7, 0.0, -6e5):
            flag, lo, hi = trust.sl_trust(ind(p), None, eps=eps, condensation=cond)
            assert np.all(np.diff(flag.astype(int)) >= 0)
            assert np.all(lo[np.isfinite(lo)] >= -1.0)


def test_add_cell_trust_with_the_shipped_rule(calibration):
    """Softening paper bed at low intensity: trusted; the same block near toppling: untrusted (the cell
    rule's calibration is the paper condensation's, pinned here)."""
    ds = linearize(Block(8.67, 0.035, 0.21), Foundation(k=2.89e7, lam=8.95e8, eps=-6e5),
                   WhiteNoise(np.array([1.14e-5, 9.79e-5, 1e-2])), trust=False, condensation="paper")
    out = trust.add_cell_trust(ds)
    assert list(out.sl_trust.values) == [Trust.trusted, Trust.check, Trust.untrusted]
    assert out.sl_error_low.values[0] < 0 < out.sl_error_high.values[0]
    assert np.isnan(out.sl_error_low.values[2]) == (int(ds.status.values[2]) != 0)


def test_add_cell_trust_result_writes_to_netcdf(tmp_path):
    ds = linearize(Block(8.67, 0.035, 0.21), Foundation(k=2.89e7, lam=8.95e8, eps=-6e5), WhiteNoise(np.array([1e-7, 1e-2])))
    out = trust.add_cell_trust(ds, trust.trust_table(None, rows=SYNTHETIC))
    out.to_netcdf(tmp_path / "r.nc")
    import xarray as xr
    with xr.open_dataset(tmp_path / "r.nc") as back:
        np.testing.assert_array_equal(back.sl_trust.values, out.sl_trust.values)
        assert back.sl_trust.attrs["flag_meanings"] == "trusted check untrusted"


def test_stationary_input_has_no_lock_in_signal():
    from screening import ConstantEnvelope
    ds = linearize(Block(8.67, 0.035, 0.21), Foundation(k=2.89e7, lam=8.95e8, eps=-6e5), WhiteNoise(1e-6, ConstantEnvelope()))
    ind = trust.indicators_from_dataset(ds)
    assert float(ind["decay_excess"]) == pytest.approx(float(ds.var_theta.isel(t=-1) / ds.peak_var_theta))
    assert float(ind["decay_excess"]) <= 1.0 + 1e-9


# ----------------------------------------------------------------------------- add_trust: the error atlas model
def _flat_model(noise, seed=0):
    """An error model fitted on synthetic atlas rows: 30 families, the error N(0, noise) everywhere."""
    from screening.analysis import error_model as em

    rng = np.random.default_rng(seed)
    fam = np.repeat(np.arange(30), 10)
    x = em.features(rng.uniform(0.001, 0.9, fam.size), rng.uniform(0.001, 0.2, fam.size), rng.uniform(0.3, 1, fam.size),
                    rng.uniform(0.5, 2, fam.size), rng.uniform(0.1, 0.45, fam.size), 10 ** rng.uniform(-4, -0.6, fam.size),
                    10 ** rng.uniform(-1.7, 0, fam.size), rng.uniform(-1e-3, 1.0, fam.size),
                    np.where(rng.uniform(size=fam.size) < 0.5, "white", "kanai_tajimi"),
                    10 ** rng.uniform(-0.3, 1.3, fam.size), 10 ** rng.uniform(0.7, 1.5, fam.size),
                    10 ** rng.uniform(-2, -0.5, fam.size), 10 ** rng.uniform(1, 2.5, fam.size))
    return em.fit_error_model(x, noise * rng.normal(size=fam.size), fam), x


def test_interval_trust_flags_from_the_interval():
    from screening.analysis import error_model as em

    model, x = _flat_model(0.01)
    q = x[:4].copy()
    q[2, em.FEATURES.index("log_tau")] = np.log(1e6)          # a constant envelope: outside the atlas
    q[3, em.FEATURES.index("log_decay_excess")] = np.nan         # an indicator that could not be computed
    flag, est, low, high = em.interval_trust(model, q, status=[0, 3, 0, 0])
    # +-1 % noise: the interval is a few per cent wide, so the point inside is trusted
    assert flag[0] == Trust.trusted and -0.25 < low[0] < est[0] < high[0] < 0.25
    assert flag[1] == Trust.untrusted and np.isnan(low[1]) and np.isnan(est[1])
    assert flag[2] == Trust.check and np.isfinite(low[2])
    assert flag[3] == Trust.check and np.isnan(low[3])
    assert em.interval_trust(model, q[:1], covered=False)[0][0] == Trust.check
    # +-100 % noise: never trusted, intervals beyond +-25 %
    wide, _ = _flat_model(1.0)
    flag, _, low, high = em.interval_trust(wide, q[:1])
    assert flag[0] != Trust.trusted and (low[0] < -0.25 or high[0] > 0.25)
    # +-100 % noise: the interval (about +-1.6 in log) reaches the fit's clip (a factor 4) both ways: it is
    # open and the point untrusted
    _, lo_log, hi_log = em.predict(wide, q[:1])
    assert lo_log[0] <= -em.LOG_CLIP and hi_log[0] >= em.LOG_CLIP
    assert flag[0] == Trust.untrusted and low[0] == -1.0 and high[0] == np.inf


def test_add_trust_is_the_shipped_error_model():
    from screening.analysis import error_model as em

    ds = linearize(Block(8.67, 0.035, 0.21), Foundation(k=2.89e7, lam=8.95e8, eps=np.array([-6e5, 0.0, 6e7])),
                   WhiteNoise(np.array([1e-7, 1e-5, 1e-2])), trust=False)
    out = trust.add_trust(ds)
    assert out.sl_trust.dims == ds.peak_var_theta.dims
    assert out.sl_trust.attrs["flag_meanings"] == "trusted check untrusted"
    x, dims, shape = em.dataset_features(ds)
    flag, est, low, high = em.interval_trust(em.shipped_model(ds.attrs["condensation"]), x,
                                             ds.status.transpose(*dims).values.ravel())
    np.testing.assert_array_equal(out.sl_trust.transpose(*dims).values.ravel(), flag)
    np.testing.assert_allclose(out.sl_error_low.transpose(*dims).values.ravel(), low)
    np.testing.assert_allclose(out.sl_error_high.transpose(*dims).values.ravel(), high)
    stopped = ds.status.values != 0
    assert np.all(out.sl_trust.values[stopped] == Trust.untrusted)
    assert np.all(np.isnan(out.sl_error_low.values[stopped]))
    ok = ~stopped
    assert np.all(out.sl_error_low.values[ok] < out.sl_error_high.values[ok])
    # linearize adds the same by default
    np.testing.assert_array_equal(linearize(Block(8.67, 0.035, 0.21), Foundation(k=2.89e7, lam=8.95e8, eps=0.0),
                                            WhiteNoise(1e-5)).sl_trust.values,
                                  out.sl_trust.sel(eps=0.0, S0=1e-5).values)


def test_add_trust_by_condensation_and_without_histories():
    ds = linearize(Block(8.67, 0.035, 0.21), Foundation(k=2.89e7, lam=8.95e8, eps=0.0),
                   WhiteNoise(np.array([1e-7, 1e-5])), condensation="virtual_work", trust=False)
    narrow, _ = _flat_model(0.01)
    wide, _ = _flat_model(1.0)
    a = trust.add_trust(ds, {"virtual_work": narrow})
    b = trust.add_trust(ds, {"virtual_work": wide})
    assert np.all((b.sl_error_high - b.sl_error_low).values > 5 * (a.sl_error_high - a.sl_error_low).values)
    none = trust.add_trust(ds, {"paper": narrow})                   # no model of this condensation
    assert np.all(none.sl_trust.values == Trust.check) and np.all(np.isnan(none.sl_error_low.values))
    bare = trust.add_trust(ds.drop_vars(["var_theta", "k_eq"]))
    assert np.all(bare.sl_trust.values == Trust.check) and np.all(np.isnan(bare.sl_error_high.values))
    with_summaries = ds.drop_vars(["var_theta", "k_eq"]).assign(k_eq_rest=ds.k_eq.isel(t=0),
                                                                 var_theta_end=ds.var_theta.isel(t=-1))
    np.testing.assert_array_equal(trust.add_trust(with_summaries).sl_trust.values, trust.add_trust(ds).sl_trust.values)


def test_model_features_of_objects_equal_those_of_the_dataset():
    from screening import KanaiTajimi
    from screening.analysis import error_model as em

    block = Block(8.67, 0.035, 0.21)
    foundation = Foundation(k=2.89e7, lam=8.95e8, eps=-6e5)
    excitation = KanaiTajimi(1e-5, omega_g=15.0, zeta_g=0.4)
    ds = linearize(block, foundation, excitation, trust=False)
    x, _, _ = em.dataset_features(ds)
    ind = {k: np.atleast_1d(v.values) for k, v in trust.indicators_from_dataset(ds).items()}
    np.testing.assert_allclose(em.model_features(ind, block, foundation, excitation), x, rtol=1e-12)
