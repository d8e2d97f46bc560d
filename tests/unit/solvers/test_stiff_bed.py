"""The stiff-bed model (screening.solvers.stiff_bed) against independent computations (its compiled
twins and contact law: test_stiff_bed_contact.py; its integrator: test_stiff_bed_kernels.py):
Housner's rigid block on an infinitely stiff bed (energy ratio per impact, period against the closed
form and the energy-integral quadrature), the bed-derived transfer loss against the coupled model's
free rocking, the quasi-static tilt against the condensation's moment law and the coupled model,
mirror symmetry, and bad input."""

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import quad

import screening
from screening.analysis.beds import lam_from_vertical_damping
from screening.core.condensation import cubic
from screening.core.model import Block, Foundation
from screening.solvers import mc_registry, stiff_bed as sb
from screening.solvers.stiff_bed import StiffBedModel

STATUE = Block(m=1200.0, b=0.25, h=0.9)
SLENDER = Block(m=500.0, b=0.1, h=1.0)


def _bed(block, k, eps=0.0, zeta_v=0.05):
    return Foundation(k=k, lam=float(lam_from_vertical_damping(k, block.m, block.b, zeta_v)), eps=eps)


BEDS = [_bed(STATUE, 1e10), Foundation(k=2.1e9, lam=1e10, eps=2e9), Foundation(k=1e10, c=2e6),
        Foundation(k=1e8, lam=1e9, eps=-1e5)]


def _free(model, block, bed, theta0, t_end, output_dt=1e-4):
    ds = screening.simulate(block, bed, np.zeros(3), dt=min(t_end / 2, 0.5), t_end=t_end, theta0=theta0, model=model,
                            output_dt=output_dt)
    return ds.t.values, ds.theta.values, ds.theta_dot.values


def _crossings(t, theta):
    """Times [s] of the sign changes of theta (linear interpolation between outputs)."""
    i = np.flatnonzero(np.sign(theta[1:]) != np.sign(theta[:-1]))
    return t[i] - theta[i] * (t[i + 1] - t[i]) / (theta[i + 1] - theta[i])


def _extreme_after_first_crossing(t, theta):
    i = np.flatnonzero(np.sign(theta) != np.sign(theta[0]))[0]
    j = np.flatnonzero(np.sign(theta[i:]) != np.sign(theta[i]))
    seg = theta[i:i + j[0]] if j.size else theta[i:]
    return float(np.max(np.abs(seg)))


# ----------------------------------------------------------------------------- compiled twins
# ----------------------------------------------------------------------------- Housner's limit
RIGID = Foundation(k=1e15, lam=0.0)


@pytest.mark.parametrize("theta0_over_alpha", [0.3, 0.6])
def test_infinitely_stiff_bed_loses_housner_energy_ratio_per_impact(theta0_over_alpha):
    alpha = STATUE.slenderness
    theta0 = theta0_over_alpha * alpha
    t, theta, _ = _free(StiffBedModel(transfer="housner"), STATUE, RIGID, theta0, 3.0, output_dt=2e-5)
    theta1 = _extreme_after_first_crossing(t, theta)
    ratio = sb.potential(theta1, STATUE, RIGID) / sb.potential(theta0, STATUE, RIGID)
    assert ratio == pytest.approx(sb.housner_restitution(STATUE) ** 2, rel=2e-3)


def test_free_rocking_period_on_a_rigid_bed_against_quadrature_and_housner():
    """Loss-free rocking of a slender block from theta0 = 0.2 alpha: the quarter period against the
    quadrature of the energy integral int dtheta / sqrt(2 (V(theta0) - V(theta)) / m_eff(theta))
    (tolerance 2e-4, the output resolution) and against Housner's closed form
    (1/p) arccosh(1 / (1 - theta0/alpha)), p^2 = m g R / I_O, exact for the linearized slender block:
    the model keeps O(theta) terms in the inertia, so within 1.5 %."""
    block, alpha = SLENDER, SLENDER.slenderness
    theta0 = 0.2 * alpha
    t, theta, _ = _free(StiffBedModel(transfer="none"), block, RIGID, theta0, 6.0, output_dt=2e-4)
    quarter = _crossings(t, theta)[0]
    v0 = sb.potential(theta0, block, RIGID)

    def integrand(th):
        m_eff = float(sb.rocking_coefficients(th, block, RIGID)[0])
        return 1.0 / math.sqrt(2.0 * max(v0 - sb.potential(th, block, RIGID), 1e-300) / m_eff)

    # the singularity at theta0 is integrable like (theta0 - theta)^-1/2: substitute theta = theta0 (1 - s^2)
    quadrature, _ = quad(lambda s: integrand(theta0 * (1 - s * s)) * 2 * theta0 * s, 0.0, 1.0, limit=200)
    assert quarter == pytest.approx(quadrature, rel=2e-4)
    radius = math.hypot(block.b, block.h)
    i_o = block.I_cm + block.m * radius**2
    p = math.sqrt(block.m * block.g * radius / i_o)
    housner = math.acosh(1.0 / (1.0 - theta0 / alpha)) / p
    assert quarter == pytest.approx(housner, rel=0.015)


# ----------------------------------------------------------------------------- transfer loss from the bed
@pytest.mark.slow
@pytest.mark.parametrize("k", [1e10, 1e11])
def test_bed_derived_transfer_loss_reproduces_the_coupled_free_rocking(k):
    """Between the table's nodes (geometric mid-points), the model's next amplitude after one transfer
    against the coupled model's: within 2 % of the amplitude (the interpolation error of the table)."""
    bed = _bed(STATUE, k)
    amps = sb.transfer_table(STATUE, bed)[4]
    for a0 in np.sqrt(amps[2:-1] * amps[3:])[::2]:
        t_end = sb._half_period_estimate(a0, STATUE, bed)
        out = {}
        for model in ("coupled", "stiff_bed"):
            t, theta, _ = _free(model, STATUE, bed, a0, t_end, output_dt=t_end / 20000)
            out[model] = _extreme_after_first_crossing(t, theta)
        assert out["stiff_bed"] == pytest.approx(out["coupled"], rel=0.02), a0


def test_bed_derived_loss_grows_with_amplitude_and_with_stiffness_towards_housner():
    """The loss depends on the amplitude (below 1 % at the three smallest nodes, up to 20 theta_ul, the most at
    0.7 alpha; non-increasing energy ratio from there within 0.005) and, at large rotations, grows with the
    bed's stiffness towards, and stays short of, Housner's plastic impact r^2 (0.80 for the statue; 0.885,
    0.846, 0.821 measured).  At every node the coupled model loses at least what this model's own contact
    damping takes over the half cycle (the ratio needs no clipping at 1)."""
    last = []
    for k in (1e10, 1e11, 1e12):
        _, log_eta, eta_coupled, eta_model, _ = sb.transfer_table(STATUE, _bed(STATUE, k))
        eta = np.exp(log_eta)
        assert np.all(eta[1:4] > 0.99) and eta[-1] < 0.95
        assert np.all(np.diff(eta[3:]) < 0.005)
        assert np.all(eta_coupled <= eta_model)
        last.append(eta[-1])
    assert last[0] > last[1] > last[2] > sb.housner_restitution(STATUE) ** 2


def test_impact_table_keys_the_bed_table_by_the_rate_of_free_rocking_at_the_crossing():
    """The node rates of transfer="impact" against the rate the loss-free model reaches at its first zero
    crossing from rest at each node amplitude (simulated, linear interpolation at the crossing): within
    0.5 % (the model's own contact damping over a quarter cycle, below 1 % of the energy past 0.01 alpha);
    the energy ratios are the bed table's."""
    bed = _bed(STATUE, 1e10)
    log_amp, log_eta, *_ = sb.transfer_table(STATUE, bed)
    log_rate, log_eta_impact = sb.impact_table(STATUE, bed)
    assert np.array_equal(log_eta_impact, log_eta)
    assert np.all(np.diff(log_rate) > 0)
    alpha = STATUE.slenderness
    for amp in np.exp(log_amp)[np.exp(log_amp) > 0.01 * alpha]:
        t_end = sb._half_period_estimate(amp, STATUE, bed) / 3
        t, theta, theta_dot = _free(StiffBedModel(transfer="none"), STATUE, bed, amp, t_end, output_dt=t_end / 40000)
        i = np.flatnonzero(np.sign(theta[1:]) != np.sign(theta[:-1]))[0]
        s_ = theta[i] / (theta[i] - theta[i + 1])
        rate = abs(theta_dot[i] + s_ * (theta_dot[i + 1] - theta_dot[i]))
        assert rate == pytest.approx(math.exp(np.interp(math.log(amp), log_amp, log_rate)), rel=5e-3), amp


@pytest.mark.parametrize("sampler", ["reference", "exact_contact"])
@pytest.mark.parametrize("pumped", [1.0, 2.0])
def test_impact_transfer_reads_the_loss_at_the_rate_the_block_hits_with(pumped, sampler):
    """A block started at A = 0.05 alpha towards zero with the kinetic energy (pumped - 1) V(A) (as a ground
    motion pumps a half cycle) hits with the energy pumped V(A): the rate ratio squared across the crossing is
    eta read at that rate (numpy interpolation of impact_table) with transfer="impact", at A with "bed"
    (transfer_table) -- equal when nothing was pumped, 1.5 % apart at twice the energy; within 2e-3.  The
    reference kernel and the exact-contact sampler alike."""
    from screening.solvers.stiff_bed_fast import FastStiffBedModel

    model_class = StiffBedModel if sampler == "reference" else FastStiffBedModel
    bed = _bed(STATUE, 1e10)
    alpha = STATUE.slenderness
    amp = 0.05 * alpha
    m_eff = float(sb.rocking_coefficients(amp, STATUE, bed)[0])
    rate0 = -math.sqrt(2.0 * (pumped - 1.0) * sb.potential(amp, STATUE, bed) / m_eff)
    log_amp, log_eta, *_ = sb.transfer_table(STATUE, bed)
    log_rate, _ = sb.impact_table(STATUE, bed)
    got = {}
    for transfer in ("bed", "impact"):
        ds = screening.simulate(STATUE, bed, np.zeros(3), dt=0.1, t_end=0.3, theta0=amp, theta_dot0=rate0,
                                model=model_class(transfer=transfer), output_dt=2e-6)
        theta, theta_dot = ds.theta.values, ds.theta_dot.values
        i = np.flatnonzero(np.sign(theta[1:]) != np.sign(theta[:-1]))[0]
        before, after = abs(theta_dot[i - 1]), abs(theta_dot[i + 2])
        got[transfer] = (after / before) ** 2
        expected = (math.exp(np.interp(math.log(before), log_rate, log_eta)) if transfer == "impact"
                    else math.exp(np.interp(math.log(amp), log_amp, log_eta)))
        assert got[transfer] == pytest.approx(expected, abs=2e-3), transfer
    if pumped == 1.0:
        assert got["impact"] == pytest.approx(got["bed"], abs=2e-3)
    else:
        assert got["bed"] - got["impact"] > 0.01


# ----------------------------------------------------------------------------- partial-contact rocking
@pytest.mark.parametrize("ratio", [0.85, 0.9, 0.93])
def test_partial_contact_rocking_under_a_sine_burst_against_the_coupled_model(ratio):
    """The calibration statue (600 kg, b = 0.2 m, h = 0.8 m) on k = 1e10, lam = 3e11 under a 2 s sine burst at
    15.6 rad/s (sin^2 envelope) of amplitude ``ratio`` g b/h: the block rocks in partial contact for 40-85 %
    of the time (~100 zero crossings, peaks 40-150 theta_ul), where the damping on the quasi-static contact
    decides the build-up.  Peak within 3 % of the coupled model's (measured +0.5, -0.8, -1.1 %; with the
    condensation's damping moment in place of the constraint's dissipation: -9, -14, -11 %)."""
    block, bed = Block(m=600.0, b=0.2, h=0.8), Foundation(k=1e10, lam=3e11)
    dt = 1e-3
    t = np.arange(0.0, 4.0, dt)
    record = ratio * block.g * block.b / block.h * np.sin(np.pi * np.clip(t / 2.0, 0, 1)) ** 2 * np.sin(15.6 * t)
    peaks = {}
    for model in ("coupled", "stiff_bed"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            peaks[model] = float(screening.simulate(block, bed, record, dt=dt, model=model).peak_abs_theta)
    assert peaks["coupled"] > 30 * float(cubic.uplift_threshold(block, bed))      # well into partial contact
    assert peaks["stiff_bed"] == pytest.approx(peaks["coupled"], rel=0.03)


# ----------------------------------------------------------------------------- quasi-static tilt
@pytest.mark.parametrize("bed", [BEDS[0], BEDS[1]], ids=["hc", "hardening"])
def test_quasi_static_tilt_against_the_condensation_moment_law_and_the_coupled_model(bed):
    """A slowly ramped constant ground acceleration a = 0.85 g b/h (above the uplift onset g b/(3h)):
    the settled tilt solves cos(theta) (K(s) s + m g h s) - m g h sin(theta) = m h cos(theta) a,
    s = sin(theta), with the cubic condensation's K (brentq on the stable, rising branch of the
    moment law), and agrees with the coupled model's settled tilt."""
    a_g = 0.85 * STATUE.g * STATUE.b / STATUE.h
    dt = 1e-3
    t = np.arange(0.0, 8.0, dt)
    ramp = -a_g * np.clip(t / 3.0, 0.0, 1.0) ** 2 * (3 - 2 * np.clip(t / 3.0, 0.0, 1.0))   # inertial x_g'' = +a_g
    mgh = STATUE.m * STATUE.g * STATUE.h

    def residual(th):
        s = math.sin(th)
        bed_moment = math.cos(th) * (float(cubic.restoring_moment(s, STATUE, bed)) + mgh * s)
        return bed_moment - mgh * s - STATUE.m * STATUE.h * math.cos(th) * a_g

    from scipy.optimize import brentq
    tu = float(cubic.uplift_threshold(STATUE, bed))
    grid = np.geomspace(tu, STATUE.slenderness, 400)
    first = np.flatnonzero(np.array([residual(x) for x in grid]) > 0.0)[0]       # the rising branch
    expected = brentq(residual, grid[first - 1], grid[first], xtol=1e-15)
    tilt = {}
    for model in ("stiff_bed", "coupled"):
        ds = screening.simulate(STATUE, bed, ramp, dt=dt, model=model, output_dt=0.01)
        tilt[model] = float(ds.theta.sel(t=slice(4.0, None)).mean())      # lightly damped in uplift: average
    assert tilt["stiff_bed"] == pytest.approx(expected, rel=1e-3)
    assert tilt["coupled"] == pytest.approx(expected, rel=3e-3)
    assert expected > 5 * tu


def test_uplift_starts_at_the_condensation_threshold():
    """Settled tilt under a constant ground acceleration just below and above the onset (the
    acceleration that holds the block at theta_ul): below it stays in full contact, above it lifts."""
    bed = BEDS[0]
    tu = float(cubic.uplift_threshold(STATUE, bed))
    onset = float(cubic.restoring_moment(tu, STATUE, bed)) / (STATUE.m * STATUE.h)
    assert onset == pytest.approx(STATUE.g * STATUE.b / (3 * STATUE.h), rel=1e-3)
    dt = 1e-3
    t = np.arange(0.0, 4.0, dt)
    for factor, lifted in ((0.98, False), (1.02, True)):
        ramp = -factor * onset * np.clip(t / 2.0, 0.0, 1.0)
        ds = screening.simulate(STATUE, bed, ramp, dt=dt, model="stiff_bed", output_dt=0.1)
        assert (abs(float(ds.theta.values[-1])) > tu) == lifted


# ----------------------------------------------------------------------------- symmetry, bad input
def test_mirror_symmetry():
    rng = np.random.default_rng(3)
    a_g = np.convolve(rng.standard_normal(4000), np.ones(25) / 5.0, mode="same") * 1.5
    bed = BEDS[0]
    pos = screening.simulate(STATUE, bed, a_g, dt=2e-3, model="stiff_bed", output_dt=0.01)
    neg = screening.simulate(STATUE, bed, -a_g, dt=2e-3, model="stiff_bed", output_dt=0.01)
    assert float(pos.peak_abs_theta) > 10 * float(pos.theta_ul)       # it rocks
    np.testing.assert_allclose(neg.theta.values, -pos.theta.values, rtol=0, atol=1e-12)


def test_soft_bed_warns_naming_the_validity_rule():
    soft = Foundation(k=1.1e6, lam=1e7)                 # theta_ul / atan(b/h) = 0.32: softer than any bed measured
    with pytest.warns(UserWarning, match=r"'stiff_bed' outside its measured validity: theta_ul_over_slenderness = "
                                         r"\S+ outside the measured \[\S+, \S+\].*model_choice.toml"):
        screening.simulate(STATUE, soft, np.zeros(3), dt=0.01, model="stiff_bed", t_end=0.05)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        screening.simulate(STATUE, _bed(STATUE, 3e6), np.zeros(3), dt=0.01, model="stiff_bed", t_end=0.05)


def test_block_that_cannot_stand_is_refused_naming_the_parameter():
    too_soft = Foundation(k=1e5, lam=1e6)              # (2/3) b^3 k < m g h
    with pytest.raises(ValueError, match=r"parameter 'foundation.k'.*cannot stand"):
        screening.simulate(STATUE, too_soft, np.zeros(3), dt=0.01, model="stiff_bed", t_end=0.05)


def test_model_registry_lists_the_stiff_bed_model():
    assert mc_registry.names()[:3] == ("coupled", "condensed", "stiff_bed")
    assert mc_registry.get("stiff_bed") is sb.STIFF_BED
    with pytest.raises(ValueError, match="parameter 'model' must be one of .*stiff_bed"):
        mc_registry.get("rigid")
    with pytest.raises(ValueError, match="parameter 'transfer'"):
        StiffBedModel(transfer="constant")


# ----------------------------------------------------------------------------- paired with the coupled model
@pytest.mark.slow
def test_paired_samples_in_full_contact_match_the_coupled_model():
    """Same seeds, same synthesized ground motions: at an intensity where the statue on k = 1e10 mostly
    stays in full contact, the samples that never lift in either model have the same peak rotation
    (both are the linear rocking oscillator there; 1 % for the coupled model's second-order
    vertical coupling) when both read the stiff-bed model's band, and 3 % with the coupled model on its
    own full band (the components above 1.5 x the full-contact rocking frequency, measured 1.6 %); the
    models agree on which samples lift at all (all but 2 of 64)."""
    bed = _bed(STATUE, 1e10)
    kw = dict(n_samples=64, seed=5, t_end=10.0, progress=False)
    exc = screening.KanaiTajimi(2.5e-4, 15.6, 0.6, band_limit_hz=None)     # the intensity as measured (idealized)
    new = screening.monte_carlo(STATUE, bed, exc, model="stiff_bed", **kw)
    tu = float(new.theta_ul)
    for ref, tol in ((screening.monte_carlo(STATUE, bed, exc, model="coupled", band=new.attrs["input_band_rad_s"],
                                            **kw), 0.01),
                     (screening.monte_carlo(STATUE, bed, exc, model="coupled", **kw), 0.03)):
        lifted_ref = ref.peak_abs_theta.values > tu
        lifted_new = new.peak_abs_theta.values > tu
        quiet = ~lifted_ref & ~lifted_new
        assert 10 <= quiet.sum() <= 60                     # both regimes present
        np.testing.assert_allclose(new.peak_abs_theta.values[quiet], ref.peak_abs_theta.values[quiet], rtol=tol)
        assert np.sum(lifted_ref != lifted_new) <= 2


@pytest.mark.slow
def test_exceedance_and_overturning_probabilities_match_the_coupled_model_on_a_stiff_bed():
    """The statue on k = 1e10 at S0 = 0.02 (most samples rock, some overturn), 120 samples of each
    model on the same ground motions: P(|theta| > a alpha), a = 0.05, 0.1, 0.3, 0.5, and P(overturn)
    within max(0.03, 2.5 standard errors of the difference), the tolerance of the scene's validity
    table (rocking responses are sensitive to the smallest perturbation, so the comparison is of
    the probabilities, not of each sample)."""
    bed = _bed(STATUE, 1e10)
    kw = dict(n_samples=120, seed=11, progress=False)
    exc = screening.KanaiTajimi(0.02, 15.6, 0.6)
    alpha = STATUE.slenderness
    probs = {}
    for model in ("coupled", "stiff_bed"):
        ds = screening.monte_carlo(STATUE, bed, exc, model=model, **kw)
        peak, over = ds.peak_abs_theta.values, ds.overturned.values
        probs[model] = np.array([np.mean((peak > a * alpha) | over) for a in (0.05, 0.1, 0.3, 0.5)]
                                + [np.mean(over)])
    p, q = probs["coupled"], probs["stiff_bed"]
    se = np.sqrt((p * (1 - p) + q * (1 - q)) / 120)
    assert 0.03 < p[-1] < 0.6 and p[2] < 0.9          # an informative intensity
    assert np.all(np.abs(p - q) <= np.maximum(0.03, 2.5 * se)), (p, q)

def test_a_softening_bed_the_model_cannot_use_says_what_to_change():
    """Issue 36 item 7: 'the bed cannot carry the block at theta0=np.float64(0.0318...) rad' named an angle the
    user never set, as a numpy repr."""
    import pytest as _pytest

    from screening import Block, Foundation
    from screening.solvers.stiff_bed import transfer_table

    with _pytest.raises(ValueError) as info:
        transfer_table(Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8, eps=-6e5))
    text = str(info.value)
    assert "np.float64" not in text and "theta0" not in text
    assert "foundation.eps" in text and 'model = "coupled"' in text
