"""The stiff-bed model's exact-contact sampler (screening.kernels.stiff_bed_fast, screening.solvers.stiff_bed_fast):
the closed-form full-contact propagator against solve_ivp, the kernel against solve_ivp of the model's equation
(with and without a transfer), its acceleration against the reference's, the batched synthesis against the
engine's, and the registered model."""

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import screening
from screening.analysis.beds import lam_from_vertical_damping
from screening.core.condensation import cubic
from screening.kernels import stiff_bed_fast as fast
from screening.core.model import Block, Foundation
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.records import Record
from screening.solvers import stiff_bed as sb
from screening.solvers import stiff_bed_fast as sf
from screening.kernels.stiff_bed_contact import rocking_acceleration_jit, stiff_record
from screening.kernels.stiff_bed_kernels import linear_propagator
from screening.solvers.synthesis import ground_acceleration_samples

STATUE = Block(m=1200.0, b=0.25, h=0.9)
BED = Foundation(k=1e10, lam=float(lam_from_vertical_damping(1e10, STATUE.m, STATUE.b, 0.05)))
CABINET = Block(m=400.0, b=0.3, h=1.0)
PADS = Foundation(k=2.1e9, eps=2e9, lam=float(lam_from_vertical_damping(2.1e9, 400.0, 0.3, 0.05)))


def _model_rhs(u=lambda s: 0.0):
    """``(theta, theta')'`` of the model's equation for solve_ivp: the compiled twin of
    ``stiff_bed.rocking_acceleration`` (held to it by test_stiff_bed_contact.py), 50x cheaper a call."""
    sp, cp = stiff_record(STATUE, BED)[0], cubic.sdof_record(STATUE, BED)[0]
    return lambda s, y: [y[1], rocking_acceleration_jit(sp, cp, y[0], y[1], u(s))]


@pytest.mark.parametrize("omega2,c", [(1.7e5, 40.0), (1.7e5, 2 * math.sqrt(1.7e5)), (1.7e5, 2000.0), (4.0, 0.0)],
                         ids=["underdamped", "critical", "overdamped", "undamped"])
def test_closed_form_step_against_solve_ivp(omega2, c):
    """x'' + c x' + omega2 x = g P(s) with a cubic input, from a nonzero state: the closed form against DOP853 at
    rtol 1e-12, within 1e-9 of the state's scale (measured 1e-13 to 1e-11)."""
    g = 0.8
    p = (0.7, -3.0, 40.0, -900.0)
    x0, v0 = 2e-5, -3e-3
    tau = 0.01 if omega2 > 100 else 1.3
    rhs = lambda s, y: [y[1], g * (p[0] + s * (p[1] + s * (p[2] + s * p[3]))) - c * y[1] - omega2 * y[0]]  # noqa
    ref = solve_ivp(rhs, (0.0, tau), [x0, v0], rtol=1e-12, atol=1e-20, method="DOP853").y[:, -1]
    x, v = fast.oscillator_step(omega2, c, g, x0, v0, *p, tau)
    w = math.sqrt(omega2)
    scale = max(abs(ref[0]), abs(ref[1]) / w, abs(x0))
    assert abs(x - ref[0]) <= 1e-9 * scale
    assert abs(v - ref[1]) <= 1e-9 * scale * w


def test_grid_maps_against_van_loan():
    """The grid interval's [Phi | Gamma] from the closed form equals the reference's matrix exponential (Van Loan)
    to 1e-10, and the last of the pieces is the whole interval."""
    m0, c0, k0, mh = 1321.0, 7357.5, 2.3e8, 1080.0
    dt = 0.005
    phi, gamma = linear_propagator(m0, c0, k0, mh, dt)
    prop = fast.grid_propagator(k0 / m0, c0 / m0, mh / m0, dt)
    scale = np.abs(np.hstack([phi, gamma])).max(axis=1, keepdims=True)
    assert np.all(np.abs(prop - np.hstack([phi, gamma])) <= 1e-10 * scale)
    pieces = fast.grid_pieces(k0 / m0, c0 / m0, mh / m0, dt)
    assert pieces.shape[0] == math.ceil(math.sqrt(k0 / m0) * dt / fast.PIECE_PHASE)
    assert np.allclose(pieces[-1], prop, rtol=0, atol=1e-12 * scale.max())


@pytest.mark.parametrize("block,bed", [(STATUE, BED), (CABINET, PADS)], ids=["statue", "cabinet pads"])
def test_acceleration_is_the_reference(block, bed):
    """One indentation solve per call (and the uplift branch written out once) gives the reference's acceleration
    (1e-12), in full contact and uplift."""
    sp, cp = stiff_record(block, bed)[0], cubic.sdof_record(block, bed)[0]
    par = fast.lifted_record(sp, cp)
    tu = float(cp["theta_ul"])
    for theta in (0.3 * tu, -0.9 * tu, 1.5 * tu, -40 * tu, 0.2 * float(block.slenderness)):
        for rate, u in ((0.0, 0.0), (0.05, 2.0), (-0.3, -4.0)):
            ref = rocking_acceleration_jit(sp, cp, theta, rate, u)
            assert fast.uplift_acceleration(sp, cp, theta, rate, u) == pytest.approx(ref, rel=1e-12, abs=1e-12)
            assert fast.lifted_acceleration(par, sp, cp, theta, rate, u) == pytest.approx(ref, rel=1e-12, abs=1e-12)


def test_series_sine_and_cosine_within_an_ulp():
    """The acceleration's sine and cosine (Taylor polynomials up to SERIES_LIMIT, math beyond) within 1.2 ulp of
    math.sin and math.cos (truncation below 1e-16; measured 1 ulp)."""
    theta = np.concatenate([np.linspace(-0.35, 0.35, 70001), np.geomspace(1e-12, fast.SERIES_LIMIT, 2001)])
    for t in theta:
        s, c = fast._sin_cos(float(t))
        assert abs(s - math.sin(t)) <= 1.2 * np.spacing(abs(math.sin(t)))
        assert abs(c - math.cos(t)) <= 1.2 * np.spacing(math.cos(t))


def _kernel(model, acc, acc_dot, dt, t_out, y0, rtol, h_max=0.01):
    integrate = model.integrator(STATUE, BED, "paper", 0.5)
    n_t = t_out.size
    out = [np.empty((1, n_t)) for _ in range(4)]
    uplift = np.zeros((1, n_t), dtype=bool)
    peak, h_min = np.zeros(1), np.zeros(1)
    status, reason, n_acc, n_rej = (np.zeros(1, dtype=np.int64) for _ in range(4))
    integrate(acc, acc_dot, dt, t_out, model.initial_state(STATUE, BED, *y0), rtol * model.state_scales(STATUE, BED),
              rtol, h_max, 10**7, *out, uplift, peak, status, reason, n_acc, n_rej, h_min)
    return out[0][0], out[1][0], int(status[0])


def test_kernel_against_solve_ivp_of_the_model():
    """A sine burst that lifts the statue off its k = 1e10 bed and rocks it through transfers, no transfer loss:
    the exact-contact kernel at rtol 1e-10 against DOP853 on the model's acceleration (rtol 1e-11) at every
    output instant of the first 1.5 s, within 1e-5 of the peak rotation (measured 1.4e-7; solve_ivp reads the kernel's input, the grid's
    cubic Hermite interpolant)."""
    dt, t_end = 0.005, 1.5
    t = np.arange(0.0, t_end + 2 * dt, dt)
    a, w = 4.0, 2 * math.pi * 3.0
    env = np.minimum(t / 0.3, 1.0)
    acc = (a * env * np.sin(w * t))[None, :]
    acc_dot = (a * (np.where(t < 0.3, 1 / 0.3, 0.0) * np.sin(w * t) + env * w * np.cos(w * t)))[None, :]
    t_out = np.arange(0.0, t_end + 1e-9, 0.05)
    theta, rate, status = _kernel(sf.FastStiffBedModel(transfer="none"), acc, acc_dot, dt, t_out, (0.0, 0.0), 1e-10)
    assert status == 0

    def u(s):                                            # the kernel's input: the grid's cubic Hermite interpolant
        j = min(int(s / dt), t.size - 2)
        x = s / dt - j
        h00, h01, h10, h11 = 2 * x**3 - 3 * x**2 + 1, 3 * x**2 - 2 * x**3, x**3 - 2 * x**2 + x, x**3 - x**2
        return h00 * acc[0, j] + h01 * acc[0, j + 1] + dt * (h10 * acc_dot[0, j] + h11 * acc_dot[0, j + 1])

    tu = float(cubic.uplift_threshold(STATUE, BED))
    ref = solve_ivp(_model_rhs(u), (0.0, t_end), [0.0, 0.0], t_eval=t_out, rtol=1e-11, atol=1e-9 * tu, method="DOP853",
                    max_step=1e-3).y[0]
    assert np.abs(ref).max() > 100 * tu                 # it rocks well beyond the partial contact
    assert np.sum(np.diff(np.sign(ref)) != 0) >= 4       # through transfers
    assert np.abs(theta - ref).max() <= 1e-5 * np.abs(ref).max()


def test_transfer_against_solve_ivp_with_an_event():
    """Free rocking from rest at 0.3 atan(b/h) through one transfer with Housner's ratio: the kernel (rtol 1e-10)
    against DOP853 to the zero crossing (event), the rate times r there, and on 0.1 s: within 1e-6 of the start
    in theta and of the rate (the transfer located in closed form at the crossing)."""
    theta0 = 0.3 * STATUE.slenderness
    rhs = _model_rhs()
    crossing = lambda t, y: y[0]  # noqa: E731
    crossing.terminal, crossing.direction = True, -1
    first = solve_ivp(rhs, (0.0, 5.0), [theta0, 0.0], events=crossing, rtol=1e-12, atol=1e-14, method="DOP853")
    t_c, rate_c = first.t_events[0][0], first.y_events[0][0][1]
    t_end = t_c + 0.1
    after = solve_ivp(rhs, (t_c, t_end), [0.0, rate_c * sb.housner_restitution(STATUE)], rtol=1e-12, atol=1e-14,
                      method="DOP853")
    theta_ref, rate_ref = after.y[:, -1]
    n_grid = 41
    acc = np.zeros((1, n_grid))
    theta, rate, status = _kernel(sf.FastStiffBedModel(transfer="housner"), acc, acc.copy(), t_end / (n_grid - 2),
                                  np.array([0.0, t_end]), (theta0, 0.0), 1e-10)
    assert status == 0
    assert abs(theta[1] - theta_ref) <= 1e-6 * theta0
    assert rate[1] == pytest.approx(rate_ref, rel=1e-6)


def test_band_samples_are_the_engines():
    """The batched synthesis gives the engine's samples (same seed, same phases) to 1e-12, and refuses a bad
    cut-off with one line naming it."""
    kt = KanaiTajimi(0.015, 15.6, 0.6)
    plan = sf.band_plan(kt, 20.0, 25.0)
    acc, rate = sf.band_samples(kt, plan, 7, [0, 3, 64])
    ref, ref_rate = ground_acceleration_samples(kt, plan, 7, [0, 3, 64])
    assert np.abs(acc - ref).max() <= 1e-12 * np.abs(ref).max()
    assert np.abs(rate - ref_rate).max() <= 1e-12 * np.abs(ref_rate).max()
    for bad in (0.0, -1.0, float("nan"), "25"):
        with pytest.raises(ValueError, match="parameter 'cutoff_hz'"):
            sf.band_plan(kt, 20.0, bad)


def test_registered_model_runs_in_the_engine_and_a_vertical_record_takes_the_reference():
    """``model="stiff_bed_fast"`` runs through monte_carlo (same validity as the reference, so no warning on the
    statue's bed), and simulate with a vertical channel gives the reference kernel's answer exactly."""
    assert screening.solvers.mc_registry.get("stiff_bed_fast") is sf.STIFF_BED_FAST
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ds = screening.monte_carlo(STATUE, BED, KanaiTajimi(0.015, 15.6, 0.6), n_samples=4, t_end=2.0,
                                   model="stiff_bed_fast", cutoff=2 * math.pi * 25, progress=False)
    assert ds.attrs["model"] == "stiff_bed_fast" and int(ds.n_used) + int(ds.n_overturned) == 4
    t = np.arange(0.0, 2.0, 0.005)
    record = 3.0 * np.sin(2 * np.pi * 2.0 * t)
    vertical = 1.0 * np.sin(2 * np.pi * 5.0 * t)
    rec = Record(record, 0.005, vertical=vertical)
    runs = [screening.simulate(STATUE, BED, rec, model=m) for m in ("stiff_bed_fast", "stiff_bed")]
    assert np.array_equal(runs[0].theta.values, runs[1].theta.values, equal_nan=True)


def test_phase_counts_add_up_to_the_attempts():
    """Every uplift attempt is counted once in a phase (by |theta| / theta_ul at its start): the phases add up to
    the accepted and rejected steps (a step cut at the re-entry is an accepted one, never redone); a block leaves
    full contact at least as often as a step is cut at its return."""
    kt = KanaiTajimi(0.015, 15.6, 0.6)
    out = sf.sample(STATUE, BED, kt, 4, t_end=4.0, seed=2, count=True)["counts"]
    names = list(fast.COUNTS)
    assert out[7:].sum() == pytest.approx(out[names.index("uplift: accepted steps")]
                                          + out[names.index("uplift: rejected steps")])
    assert 0 < out[names.index("uplift: steps cut at the re-entry")] <= out[names.index("exits from full contact")]


def test_reentry_on_the_dense_output_against_solve_ivp():
    """Free rocking from rest at 20 theta_ul, all of it in partial and full contact (no transfer loss): every step
    that returns to full contact is cut at the root of its dense output; the kernel (rtol 1e-10) against DOP853 on
    the model's acceleration (rtol 1e-12) every millisecond over 0.3 s, through the re-entries, within 1e-6 of the
    start."""
    tu = float(cubic.uplift_threshold(STATUE, BED))
    theta0, t_end = 20.0 * tu, 0.3
    t_out = np.linspace(0.0, t_end, 301)
    ref = solve_ivp(_model_rhs(), (0.0, t_end), [theta0, 0.0], t_eval=t_out, rtol=1e-12, atol=1e-9 * tu, method="DOP853",
                    max_step=1e-4).y[0]
    assert np.sum(np.diff(np.sign(np.abs(ref) - tu)) != 0) >= 4        # in and out of full contact
    n_grid = 61
    acc = np.zeros((1, n_grid))
    theta, _, status = _kernel(sf.FastStiffBedModel(transfer="none"), acc, acc.copy(), t_end / (n_grid - 2), t_out,
                               (theta0, 0.0), 1e-10)
    assert status == 0
    assert np.abs(theta - ref).max() <= 1e-6 * theta0


@pytest.mark.slow
@pytest.mark.parametrize("transfer", ["bed", "impact"])
def test_paired_statistics_against_the_reference(transfer):
    """200 paired samples of the statue on k = 1e10 (Kanai-Tajimi S0 = 0.015, 25 Hz), with either transfer law:
    every exceedance and the overturning probability within 2.5 paired standard errors of the reference
    kernel's (the benchmark benchmarks/bench_stiff_bed_fast.py holds 2,000 samples per case to 1.5)."""
    kt = KanaiTajimi(0.015, 15.6, 0.6)
    models = (sf.FastStiffBedModel(transfer=transfer), sb.StiffBedModel(transfer=transfer))
    runs = [sf.sample(STATUE, BED, kt, 200, seed=3, model=m) for m in models]
    alpha = float(STATUE.slenderness)
    for a in (0.05, 0.1, 0.3, None):
        ind = [(r["peak"] > a * alpha) | r["overturned"] if a else r["overturned"] for r in runs]
        d = ind[0].astype(float) - ind[1]
        se = max(d.std(ddof=1) / math.sqrt(d.size), 1.0 / d.size)
        assert abs(d.mean()) <= 2.5 * se


def test_exit_from_a_piece_that_starts_on_theta_ul_is_the_return():
    """A piece that starts on -theta_ul moving inward, pulled out again by the ground (equilibrium at -2 theta_ul):
    the exit located is the return (solve_ivp's event, DOP853 at rtol 1e-12, within 1e-6 of it), never the start,
    where the bracket's low end lies (the stall of a sample that used its whole step budget)."""
    omega2, c, g, tu = 7.885e5, 12.2, 0.8176, 9.4176e-7
    p0 = -2.0 * tu * omega2 / g
    x0, v0, hi = -tu, 9.8e-5, 5.2e-4
    osc = np.array([omega2, c, g, math.sqrt(omega2)])
    x_hi = fast.oscillator_step(omega2, c, g, x0, v0, p0, 0.0, 0.0, 0.0, hi)[0]
    assert x_hi < -tu                                  # the piece ends outside: an exit to locate
    s, x, _ = fast._locate(osc, x0, v0, p0, 0.0, 0.0, 0.0, 0.0, hi, x_hi + tu, -tu)

    def leaves(_, y):
        return y[0] + tu
    leaves.direction = -1.0
    ref = solve_ivp(lambda _, y: [y[1], g * p0 - c * y[1] - omega2 * y[0]], (1e-9, hi),
                    fast.oscillator_step(omega2, c, g, x0, v0, p0, 0.0, 0.0, 0.0, 1e-9), events=leaves,
                    rtol=1e-12, atol=1e-20, method="DOP853").t_events[0]
    assert ref.size == 1 and ref[0] > 1e-5
    assert s == pytest.approx(ref[0], rel=1e-6) and x == -tu


def test_a_sample_grazing_theta_ul_does_not_stall():
    """Sample 9 of seed 1, the statue on k = 1e11 at rtol 1e-6, re-enters full contact on theta_ul with the ground
    pulling it out again: it used its whole budget of 5 million steps at one instant; it finishes now, within 10x
    the median sample's steps (about 13,000)."""
    bed = Foundation(k=1e11, lam=float(lam_from_vertical_damping(1e11, STATUE.m, STATUE.b, 0.05)))
    out = sf.sample(STATUE, bed, KanaiTajimi(0.015, 15.6, 0.6), 1, cutoff_hz=25.0, seed=1, rtol=1e-6, first=9)
    assert out["status"][0] == 0
    assert out["n_steps"][0] < 130_000
