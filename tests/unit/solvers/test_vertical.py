"""Vertical ground acceleration in the Monte Carlo models (coupled, condensed, stiff-bed).

Checked against independent computations: a constant vertical acceleration ``a_v`` against the same
model built with gravity ``g + a_v`` (the coupled model exactly, the stiff-bed and condensed laws by the
linear Winkler bed's similarity in the weight); a zero vertical channel bit for bit against the
horizontal-only path; the static indentation ``m (g + a_v) / (2 b k)``; the static uplift threshold
``(g + a_v) b / h`` of a slow horizontal ramp; lift-off (``g + a_v < 0``): the coupled block flies and
lands, the condensed and stiff-bed models stop with the ``lift_off`` reason.
"""

import math

import numpy as np
import pytest

import screening
from screening.analysis.beds import lam_from_vertical_damping
from screening.core.condensation import cubic
from screening.core.model import Block, Foundation
from screening.core.records import Record
from screening.solvers import mc_registry, stiff_bed as sb
from screening.kernels import mcs_kernels as kern
from screening.core.status import DivergenceReason

G = 9.81
STATUE = Block(m=1200.0, b=0.25, h=0.9, g=G)
WINKLER = Foundation(k=1e10, c=2e6)                       # eps = 0, rate damping: the similarity is exact
STIFF = Foundation(k=1e10, lam=float(lam_from_vertical_damping(1e10, STATUE.m, STATUE.b, 0.05)))
SOFT = Foundation(k=1e9, lam=float(lam_from_vertical_damping(1e9, STATUE.m, STATUE.b, 0.05)))


def _with_g(block, g):
    return Block(m=block.m, b=block.b, h=block.h, I_cm=block.I_cm, g=g)


def _integrate(mc, block, bed, y_init, a_g, a_v, dt, t_out, condensation="paper", scales_of=None, integrator="dopri"):
    """``(theta, theta_dot, z_cb, status, reason)`` of one sample of ``mc`` from ``y_init`` under the
    ground accelerations ``a_g`` (horizontal, usual sign) and ``a_v`` (vertical, up; None: no channel);
    ``scales_of``: the block whose error scales are used (default ``block``)."""
    acc = np.ascontiguousarray(-np.asarray(a_g, float)[None, :])
    rate = np.ascontiguousarray(np.gradient(acc[0], dt, edge_order=2)[None, :])
    vertical = None
    if a_v is not None:
        a_v = np.asarray(a_v, float)
        vertical = (np.ascontiguousarray(a_v[None, :]),
                    np.ascontiguousarray(np.gradient(a_v, dt, edge_order=2)[None, :]))
    out = [np.empty((1, t_out.size)) for _ in range(4)]
    uplift = np.zeros((1, t_out.size), dtype=bool)
    peak, h_min = np.zeros(1), np.zeros(1)
    status, reason, n_acc, n_rej = (np.zeros(1, dtype=np.int64) for _ in range(4))
    integrate = mc.integrator(block, bed, condensation, 0.5, integrator)
    scale = mc.default_rtol * mc.state_scales(block if scales_of is None else scales_of, bed)
    integrate(acc, rate, dt, t_out, np.ascontiguousarray(y_init, float), scale, mc.default_rtol, min(dt, 0.005),
              10**8, *out, uplift, peak, status, reason, n_acc, n_rej, h_min, vertical=vertical)
    return out[0][0], out[1][0], out[2][0], int(status[0]), int(reason[0])


def _pulse(t, amplitude, t0, width):
    """A half-sine pulse of ``amplitude`` from ``t0`` lasting ``width`` [s]."""
    x = (t - t0) / width
    return np.where((x > 0) & (x < 1), amplitude * np.sin(np.pi * np.clip(x, 0, 1)), 0.0)


def _ramp(t, t0, t1):
    """0 before ``t0``, 1 after ``t1``, smooth (``3 x^2 - 2 x^3``) between."""
    x = np.clip((t - t0) / (t1 - t0), 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


# ----------------------------------------------------------------------------- right-hand sides
@pytest.mark.parametrize("a_v", [-0.5 * G, 0.3 * G])
def test_stiff_bed_law_under_a_v_is_the_law_built_with_g_plus_a_v(a_v):
    """Numpy reference and compiled twin under ``a_v`` against the model rebuilt with gravity ``g + a_v``
    (the linear Winkler bed with rate damping is similar in the weight: exact)."""
    heavy = _with_g(STATUE, G + a_v)
    sp, cp = sb.stiff_record(STATUE, WINKLER)[0], cubic.sdof_record(STATUE, WINKLER)[0]
    tu = float(cubic.uplift_threshold(STATUE, WINKLER))
    for theta in (0.0, 0.3 * tu, -0.9 * tu, 1.2 * tu, -3 * tu, 40 * tu, -1e-3, 0.05, -0.2):
        for theta_dot in (0.0, 0.4, -2.0):
            rebuilt = float(sb.rocking_acceleration(theta, theta_dot, 1.3, heavy, WINKLER))
            ref = float(sb.rocking_acceleration(theta, theta_dot, 1.3, STATUE, WINKLER, a_v))
            jit = sb.rocking_acceleration_jit(sp, cp, theta, theta_dot, 1.3, a_v)
            assert ref == pytest.approx(rebuilt, rel=1e-9, abs=1e-6)
            assert jit == pytest.approx(ref, rel=1e-9, abs=1e-6)


@pytest.mark.parametrize("bed", [STIFF, Foundation(k=2.1e9, lam=1e10, eps=2e9)], ids=["hc", "hardening"])
def test_stiff_bed_compiled_twin_under_a_v_equals_the_numpy_reference(bed):
    sp, cp = sb.stiff_record(STATUE, bed)[0], cubic.sdof_record(STATUE, bed)[0]
    tu = float(cubic.uplift_threshold(STATUE, bed))
    for a_v in (-0.6 * G, 0.4 * G):
        for theta in (0.2 * tu, -2 * tu, 1e-3, -0.1):
            ref = float(sb.rocking_acceleration(theta, -0.7, 0.4, STATUE, bed, a_v))
            assert sb.rocking_acceleration_jit(sp, cp, theta, -0.7, 0.4, a_v) == pytest.approx(ref, rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("a_v", [-0.5 * G, 0.3 * G])
def test_condensed_law_under_a_v_is_the_law_built_with_g_plus_a_v(a_v):
    heavy = _with_g(STATUE, G + a_v)
    cond = screening.core.condensation.get("cubic")
    p, p_heavy = kern.model_record(STATUE, WINKLER, cond), kern.model_record(heavy, WINKLER, cond)
    rec, rec_heavy = cubic.sdof_record(STATUE, WINKLER)[0], cubic.sdof_record(heavy, WINKLER)[0]
    tu = float(cubic.uplift_threshold(STATUE, WINKLER))
    for theta in (0.4 * tu, -1.3 * tu, 25 * tu, -0.05):
        want = kern.condensed_acceleration(cubic.damping_stiffness_jit, rec_heavy, theta, 0.3, 0.7, p_heavy)
        got = kern.condensed_acceleration(cubic.damping_stiffness_jit, rec, theta, 0.3, 0.7, p, a_v)
        assert got == pytest.approx(want, rel=1e-9, abs=1e-6)


# ----------------------------------------------------------------------------- integrated samples
def test_a_zero_vertical_channel_is_bit_identical_to_the_horizontal_only_path():
    dt = 0.005
    t = np.arange(0.0, 3.0, dt)
    a_g = 3.0 * np.sin(2 * np.pi * 1.5 * t) * np.exp(-0.5 * t)
    t_out = np.arange(0.0, 2.9, 0.01)
    coupled, condensed = mc_registry.get("coupled"), mc_registry.get("condensed")
    cases = [(coupled, SOFT, "paper", "dopri"), (coupled, SOFT, "paper", "rodas"), (condensed, SOFT, "cubic", "dopri"),
             (condensed, SOFT, "cubic", "rodas"), (mc_registry.get("stiff_bed"), STIFF, "paper", "dopri")]
    for mc, bed, cond, method in cases:
        y0 = mc.initial_state(STATUE, bed)
        none = _integrate(mc, STATUE, bed, y0, a_g, None, dt, t_out, cond, integrator=method)
        zeros = _integrate(mc, STATUE, bed, y0, a_g, np.zeros_like(a_g), dt, t_out, cond, integrator=method)
        assert np.max(np.abs(none[0])) > 1e-4                    # it rocked
        for a, b in zip(none[:3], zeros[:3]):
            np.testing.assert_array_equal(a, b)
        assert none[3:] == zeros[3:]


@pytest.mark.parametrize("model,bed,method", [("coupled", SOFT, "dopri"), ("coupled", SOFT, "rodas"),
                                              ("stiff_bed", WINKLER, "dopri")])
def test_constant_a_v_equals_the_model_with_g_plus_a_v(model, bed, method):
    """A horizontal pulse under a constant ``a_v = -0.3 g`` against the same model built with gravity
    ``0.7 g`` from the same state (the stiff-bed model with Housner's transfer, which does not depend on g)."""
    mc = mc_registry.get(model) if model == "coupled" else sb.StiffBedModel(transfer="housner")
    if model == "stiff_bed":
        mc.default_rtol = 1e-7           # the tolerance of the comparison below (the model's default is looser)
    a_v = -0.3 * G
    light = _with_g(STATUE, G + a_v)
    dt = 0.005
    t = np.arange(0.0, 3.0, dt)
    a_g = _pulse(t, 0.2 * G, 0.2, 0.6)
    t_out = np.arange(0.0, 2.9, 0.01)
    y0 = mc.initial_state(light, bed)
    want = _integrate(mc, light, bed, y0, a_g, None, dt, t_out, integrator=method)
    got = _integrate(mc, STATUE, bed, y0, a_g, np.full_like(a_g, a_v), dt, t_out, scales_of=light, integrator=method)
    assert want[3] == got[3] == kern.STATUS_OK
    peak = np.max(np.abs(want[0]))
    assert peak > 50 * float(cubic.uplift_threshold(light, bed))          # it rocked well beyond uplift
    # to the solver's tolerance, and to where a transfer falls within a step (the stiff-bed model applies
    # its velocity ratio at the end of the step that crossed zero; steps differ: adaptive against exact)
    np.testing.assert_allclose(got[0], want[0], rtol=0, atol=(1e-3 if model == "stiff_bed" else 1e-6) * peak)
    # and the same pulse without the vertical acceleration is a different response
    assert np.max(np.abs(_integrate(mc, STATUE, bed, y0, a_g, None, dt, t_out)[0] - want[0])) > 0.05 * peak


@pytest.mark.parametrize("a_v", [-0.5 * G, 0.3 * G])
def test_coupled_static_indentation_follows_the_weight(a_v):
    """After a slow ramp to a constant ``a_v`` the coupled block rests at ``m (g + a_v) / (2 b k)`` (eps = 0)."""
    dt = 0.002
    t = np.arange(0.0, 1.0, dt)
    rec = Record(np.zeros_like(t), dt, vertical=a_v * _ramp(t, 0.0, 0.5))
    ds = screening.simulate(STATUE, SOFT, rec, model="coupled", output_dt=0.01)
    want = STATUE.m * (G + a_v) / (2 * STATUE.b * SOFT.k)
    assert float(ds.z_cb[-1]) == pytest.approx(want, rel=1e-4)
    assert float(ds.z_cb[0]) == pytest.approx(STATUE.m * G / (2 * STATUE.b * SOFT.k), rel=1e-9)
    assert bool(ds.lift_off) is False and ds.attrs["vertical_ground_motion"].startswith("used")


@pytest.mark.parametrize("model", ["coupled", "stiff_bed"])
def test_downward_ground_acceleration_lowers_the_uplift_threshold_to_g_plus_a_v_b_over_h(model):
    """A slow horizontal ramp to a constant acceleration ``A``: at ``A = 0.7 g b/h`` the block stands under
    the horizontal component alone and overturns with ``a_v = -0.5 g`` (threshold ``(g + a_v) b/h = 0.5 g b/h``);
    at ``A = 0.4 g b/h`` (0.8 of the lowered threshold) it stands with both."""
    dt = 0.005
    t = np.arange(0.0, 6.0, dt)
    alpha = float(STATUE.slenderness)
    rigid = G * STATUE.b / STATUE.h

    def run(fraction, a_v):
        rec = Record(fraction * rigid * _ramp(t, 1.0, 3.0), dt, vertical=a_v * _ramp(t, 0.0, 1.0))
        return screening.simulate(STATUE, STIFF, rec, model=model, output_dt=0.01)

    alone = run(0.7, 0.0)
    assert not bool(alone.overturned) and float(alone.peak_abs_theta) < 0.05 * alpha
    both = run(0.7, -0.5 * G)
    assert bool(both.overturned)
    below = run(0.4, -0.5 * G)
    assert not bool(below.overturned) and float(below.peak_abs_theta) < 0.05 * alpha
    assert float(below.peak_abs_theta) > float(run(0.4, 0.0).peak_abs_theta)     # and it tilts further


# ----------------------------------------------------------------------------- lift-off
def _lift_off_record():
    """At rest, then a vertical pulse to ``-1.5 g`` (``g + a_v`` below zero for about 0.04 s around 0.55 s)."""
    dt = 0.001
    t = np.arange(0.0, 1.5, dt)
    a_v = _pulse(t, -1.5 * G, 0.5, 0.1)
    return Record(np.zeros_like(t), dt, vertical=a_v), float(t[np.flatnonzero(G + a_v < 0.0)[0]])


def test_coupled_block_flies_and_lands_when_the_ground_drops_faster_than_g():
    from screening.core.physics.contact import REGIME_FLIGHT, REGIME_FULL_CONTACT

    rec, t_lift = _lift_off_record()
    ds = screening.simulate(STATUE, SOFT, rec, model="coupled", output_dt=0.002, theta0=1e-4)
    assert ds.attrs["status"] == "ok" and bool(ds.lift_off)
    assert np.all(np.isfinite(ds.theta)) and np.all(np.isfinite(ds.z_cb))
    regime = ds.contact_regime.values
    flying = np.flatnonzero(regime == REGIME_FLIGHT)
    assert flying.size and float(ds.t[flying[0]]) >= t_lift - 0.002          # not before g + a_v < 0
    assert regime[-1] != REGIME_FLIGHT and np.any(regime[flying[-1]:] == REGIME_FULL_CONTACT)   # it landed
    # against free flight from rest at the instant g + a_v turns negative (the bed's 2e-5 m indentation and
    # its unloading ignored): relative height z'' = g + a_v back to zero
    dt = 1e-5
    t = np.arange(t_lift, 1.5, dt)
    accel = G + _pulse(t, -1.5 * G, 0.5, 0.1)
    rate = np.concatenate(([0.0], np.cumsum(0.5 * (accel[1:] + accel[:-1])) * dt))
    height = np.concatenate(([0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1])) * dt))
    landing = t[np.flatnonzero((height > 0.0) & (t > t_lift + 0.01))[0]]
    first_landing = flying[0] + np.flatnonzero(regime[flying[0]:] != REGIME_FLIGHT)[0]
    assert float(ds.t[first_landing]) == pytest.approx(landing, abs=0.01)          # (then it may bounce)
    assert float(ds.t[flying[0]]) == pytest.approx(t_lift, abs=0.01)


@pytest.mark.parametrize("model,bed", [("condensed", SOFT), ("stiff_bed", STIFF)])
def test_models_without_flight_stop_at_lift_off(model, bed):
    rec, t_lift = _lift_off_record()
    ds = screening.simulate(STATUE, bed, rec, model=model, output_dt=0.002, theta0=1e-4)
    assert ds.attrs["status"] == f"diverged: {DivergenceReason.lift_off.meaning}"
    assert bool(ds.diverged) and bool(ds.lift_off) and not bool(ds.overturned)
    finite = np.isfinite(ds.theta.values)
    t_stop = float(ds.t[finite][-1])
    assert t_lift - 0.002 <= t_stop <= t_lift + 0.01                      # stopped where the ground fell away
    assert np.all(finite[:np.flatnonzero(~finite)[0]])
    assert math.isfinite(float(ds.peak_abs_theta))
