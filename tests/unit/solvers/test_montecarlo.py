"""Monte Carlo engine (screening.solvers.montecarlo and its compiled kernels).

Statistical checks use a fixed seed and tolerances of 3 standard errors of the estimate
(the dataset's own ``var_theta_se``, i.e. ``sqrt((m4 - (n-3)/(n-1) s^4)/n)``).
"""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from screening import linearize
from screening.solvers import schema
from screening.kernels import mcs_kernels as kern
from screening.solvers import montecarlo as mc
from screening.core.condensation import get as get_condensation
from screening.core.condensation.paper import damping_inner, uplift_threshold
from screening.core.physics.contact import rest_indentation
from screening.core.model.excitation import ConstantEnvelope, Envelope
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.core.model import Block, Foundation
from screening.solvers.mc_models import state_scales
from screening.solvers.montecarlo import ensemble_statistics, monte_carlo

BLOCK = Block(m=8.67, b=0.035, h=0.21)
HC = Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
WHITE = WhiteNoise(S0=2.4e-5, envelope=Envelope(4.0, 2.0))
SLENDERNESS = math.atan2(BLOCK.b, BLOCK.h)


def small_run(**kw):
    args = dict(n_samples=6, model="coupled", t_end=1.0, dt=0.05, seed=3, progress=False)
    args.update(kw)
    return monte_carlo(BLOCK, args.pop("foundation", HC), args.pop("excitation", WHITE), **args)


# ---------------------------------------------------------------- validation, before any work
@pytest.fixture
def no_work(monkeypatch):
    """Make any synthesis fail loudly: validation must happen before it."""
    def boom(*a, **k):
        raise AssertionError("work started before validation")
    monkeypatch.setattr(mc, "spectral_plan", boom)
    monkeypatch.setattr(mc, "stationary_samples", boom)


@pytest.mark.parametrize("kwargs, name", [
    (dict(n_samples=1), "n_samples"), (dict(n_samples=0), "n_samples"), (dict(n_samples=2.5), "n_samples"),
    (dict(n_samples=100.0), "n_samples"), (dict(n_samples="10"), "n_samples"), (dict(n_samples=True), "n_samples"),
    (dict(model="rigid"), "model"), (dict(model=None), "model"),
    (dict(seed=-1), "seed"), (dict(seed=1.5), "seed"), (dict(seed="0"), "seed"), (dict(seed=None), "seed"),
    (dict(t_end=-1.0), "t_end"), (dict(dt=0.0), "dt"), (dict(dt=0.03), "dt"),
    (dict(rtol=0.0), "rtol"), (dict(rtol="fast"), "rtol"), (dict(rtol=True), "rtol"),
    (dict(rtol=float("nan")), "rtol"), (dict(chunk_size=0), "chunk_size"), (dict(cutoff=-5.0), "cutoff"),
    (dict(progress="yes"), "progress"), (dict(max_steps=1.5), "max_steps"),
    (dict(thresholds=-0.01), "thresholds"), (dict(thresholds=[0.01, 0.01]), "thresholds"),
    (dict(thresholds=["a"]), "thresholds"), (dict(thresholds=[]), "thresholds"),
])
def test_bad_arguments_raise_before_any_work(no_work, kwargs, name):
    args = dict(n_samples=10**12, model="coupled", seed=0)     # a huge run if validation were late
    args.update(kwargs)
    with pytest.raises(ValueError, match=f"'{name}'"):
        monte_carlo(BLOCK, HC, WHITE, **args)


def test_unknown_numerics_option_and_array_parameters_raise(no_work):
    with pytest.raises(ValueError, match="unknown numerics option.*'step'"):
        monte_carlo(BLOCK, HC, WHITE, n_samples=10, step=1e-3)
    with pytest.raises(ValueError, match="'block.m'"):
        monte_carlo(Block(m=[8.67, 9.0], b=0.035, h=0.21), HC, WHITE, n_samples=10)
    with pytest.raises(ValueError, match="cannot carry"):
        monte_carlo(BLOCK, Foundation(k=2.89e7, lam=1.0, eps=-1e11), WHITE, n_samples=10)


# ---------------------------------------------------------------- the compiled integrator (equations: test_mcs_equations.py)
def _run_kernel(model, acc, t_out, foundation, y_init, rtol=1e-8, dt_grid=1e-3, max_flight_time=0.5,
                condensation="paper"):
    n_t = t_out.size
    acc = np.atleast_2d(acc)
    outs = [np.empty((1, n_t)) for _ in range(4)]
    uplift = np.zeros((1, n_t), dtype=bool)
    flags = [np.zeros(1), np.zeros(1, np.int64), np.zeros(1, np.int64), np.zeros(1, np.int64),
             np.zeros(1, np.int64), np.zeros(1)]
    cond = get_condensation(condensation)
    p = kern.model_record(BLOCK, foundation, cond, max_flight_time)
    sdof = cond.sdof_kernel(BLOCK, foundation)
    scale = rtol * state_scales(BLOCK, foundation)
    kern.chunk_integrator(sdof.record.dtype)(model, sdof.damping_stiffness, sdof.record, (acc, kern.NO_VERTICAL),
                                             (np.zeros_like(acc), kern.NO_VERTICAL), dt_grid, t_out, p[None],
                                             np.asarray(y_init, float), scale, rtol, 0.005, 10**7, *outs, uplift,
                                             *flags, kern.NO_PROPAGATOR, np.zeros((0, 4), np.int64))
    return outs, flags


def test_integrator_reproduces_the_linear_step_response():
    """Condensed model, eps = 0, constant ground acceleration small enough to stay below theta_ul."""
    foundation = Foundation(k=2.89e7, lam=8.95e8, eps=0.0)
    ms = BLOCK.m_sdof
    k1 = 2 / 3 * BLOCK.b**3 * foundation.k - BLOCK.m * BLOCK.g * BLOCK.h
    w, zeta = math.sqrt(k1 / ms), damping_inner(BLOCK, foundation) / (2 * math.sqrt(k1 * ms))
    a0 = 0.3 * uplift_threshold(BLOCK, foundation) * k1 / (BLOCK.m * BLOCK.h)   # static theta = 0.3 theta_ul
    t_out = np.linspace(0.0, 2.0, 41)
    outs, flags = _run_kernel(kern.MODEL_CONDENSED, np.full(2100, a0), t_out, foundation, [0, 0, 0, 0])
    theta_static = BLOCK.m * BLOCK.h * a0 / k1
    wd = w * math.sqrt(1 - zeta**2)
    exact = theta_static * (1 - np.exp(-zeta * w * t_out) * (np.cos(wd * t_out)
                                                             + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t_out)))
    np.testing.assert_allclose(outs[0][0], exact, rtol=0, atol=1e-6 * theta_static)
    assert flags[1][0] == kern.STATUS_OK
    first_peak = theta_static * (1 + math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2)))   # at t = pi/wd
    assert flags[0][0] == pytest.approx(first_peak, rel=1e-3)      # peak over all steps, not only outputs
    assert flags[0][0] > np.max(np.abs(outs[0][0])) + 1e-3 * theta_static


def _coupled_energy(theta, theta_dot, z, z_dot, foundation):
    """Kinetic + gravity + bed energy [J] of the coupled model (the Lagrangian behind eqs. 7–8)."""
    m, g, h, I, b = BLOCK.m, BLOCK.g, BLOCK.h, BLOCK.I_cm, BLOCK.b
    s, c = math.sin(theta), math.cos(theta)
    kinetic = 0.5 * m * ((h * theta_dot * c) ** 2 + (z_dot + h * theta_dot * s) ** 2) + 0.5 * I * theta_dot**2
    gravity = m * g * (h * c - z)
    def density(u):
        zz = z + u * s
        return 0.5 * foundation.k * zz**2 + 0.25 * foundation.eps * foundation.k * zz**4 if zz > 0 else 0.0
    edges = [-z / s] if s != 0 and abs(z / s) < b else None
    bed = quad(density, -b, b, points=edges, epsabs=0, epsrel=1e-12)[0]
    return kinetic + gravity + bed


@pytest.mark.parametrize("foundation", [Foundation(k=2.89e7, lam=0.0, eps=6e7),
                                        Foundation(k=2.89e7, c=0.0, eps=-6e5)], ids=["hc", "winkler"])
def test_undamped_coupled_model_conserves_energy_through_uplift_and_impacts(foundation):
    """With no dashpots eqs. (7)–(8) are conservative: a strong independent check of the
    resultants, the equations and the integrator in every contact regime."""
    t_out = np.linspace(0.0, 1.5, 31)
    z0 = rest_indentation(BLOCK, foundation)
    outs, flags = _run_kernel(kern.MODEL_COUPLED, np.zeros(1600), t_out, foundation, [0.0, 0.6, z0, 0.0],
                              rtol=1e-9)
    theta, theta_dot, z, z_dot = (o[0] for o in outs)
    assert flags[1][0] == kern.STATUS_OK
    assert np.max(np.abs(theta)) > 10 * uplift_threshold(BLOCK, foundation)     # deep into uplift
    assert np.min(z - BLOCK.b * np.abs(np.sin(theta))) < 0.0
    energy = np.array([_coupled_energy(*s, foundation) for s in zip(theta, theta_dot, z, z_dot)])
    kinetic0 = 0.5 * BLOCK.m_sdof * 0.6**2
    assert np.max(np.abs(energy - energy[0])) < 1e-6 * kinetic0


# ---------------------------------------------------------------- the dataset
def test_dataset_layout_units_and_attributes(tmp_path):
    ds = small_run(n_samples=5, model="condensed")
    assert ds.attrs["status"] == "ok"
    np.testing.assert_allclose(ds.t.values, np.arange(21) * 0.05)
    assert ds.t.attrs == schema.TIME
    units = {"var_theta": "rad2", "var_theta_dot": "rad2 s-2", "cov_theta_theta_dot": "rad2 s-1", "p_uplift": "1",
             "var_theta_se": "rad2", "var_theta_dot_se": "rad2 s-2", "peak_abs_theta": "rad"}
    for name, unit in units.items():
        assert ds[name].attrs["units"] == unit and ds[name].attrs["long_name"]
    for name in ("var_theta", "var_theta_dot", "cov_theta_theta_dot", "p_uplift", "var_theta_se"):
        assert ds[name].dims == ("t",) and np.all(np.isfinite(ds[name]))
    for name in ("peak_abs_theta", "overturned", "diverged"):
        assert ds[name].dims == ("sample",) and ds[name].size == 5
    assert ds.overturned.dtype == bool and ds.diverged.dtype == bool
    assert int(ds.n_used) + int(ds.n_overturned) + int(ds.n_diverged) == 5
    assert ds.var_theta[0] == 0.0 and float(ds.var_theta.max()) > 0.0          # starts from rest
    assert np.all(ds.peak_abs_theta > 0)
    for key in ("model", "n_samples", "seed", "rtol", "dt_integration_mean", "cutoff_rad_s",
                "intensity_convention", "statistics"):
        assert key in ds.attrs
    # the model parameters are scalar coordinates (they were attributes, S0 and block_m-style names)
    assert ds.attrs["model"] == "condensed" and ds.attrs["n_samples"] == 5 and float(ds["S0"]) == 2.4e-5
    for name in ("m", "b", "h", "I_cm", "g", "k", "lam", "eps", "S0", "T1", "T2"):
        assert name in ds.coords and ds[name].ndim == 0 and ds[name].attrs["units"] == schema.PARAMETERS[name]["units"]
    assert 0 < ds.attrs["dt_integration_mean"] < 0.05
    for value in ds.attrs.values():
        assert isinstance(value, (int, float, str))                              # plain numbers / strings
    ds.to_netcdf(tmp_path / "mcs.nc")
    import xarray as xr
    with xr.open_dataset(tmp_path / "mcs.nc") as back:
        np.testing.assert_array_equal(back.var_theta.values, ds.var_theta.values)
        assert back.attrs["status"] == "ok"


def test_reproducible_and_independent_of_chunking():
    a = small_run(chunk_size=64)
    b = small_run(chunk_size=2)
    c = small_run(chunk_size=64, seed=4)
    for name in ("var_theta", "var_theta_dot", "cov_theta_theta_dot", "p_uplift", "peak_abs_theta"):
        np.testing.assert_array_equal(a[name].values, b[name].values)
    assert not np.allclose(a.var_theta.values[1:], c.var_theta.values[1:])


@pytest.mark.parametrize("model", ["coupled", "condensed"])
def test_kanai_tajimi_and_winkler_runs(model):
    kt = KanaiTajimi(S0=2.5e-4, omega_g=10.0, zeta_g=0.4, envelope=Envelope(4.0, 2.0))
    ds = small_run(model=model, excitation=kt, foundation=Foundation(k=2.89e7, c=2e4, eps=-6e5))
    assert ds.attrs["status"] == "ok" and float(ds["omega_g"]) == 10.0
    assert np.all(np.isfinite(ds.var_theta)) and float(ds.var_theta[-1]) > 0


def test_statistics_formulas():
    rng = np.random.default_rng(1)
    theta = rng.normal(size=(50, 3))
    theta_dot = rng.normal(size=(50, 3)) + theta
    uplift = theta > 1.0
    used = np.ones(50, bool)
    used[:5] = False
    st = ensemble_statistics(theta, theta_dot, uplift, used)
    x, v = theta[used], theta_dot[used]
    np.testing.assert_allclose(st["var_theta"], x.var(axis=0, ddof=1))
    np.testing.assert_allclose(st["cov_theta_theta_dot"], [np.cov(x[:, j], v[:, j])[0, 1] for j in range(3)])
    n = 45
    m4 = np.mean((x - x.mean(axis=0)) ** 4, axis=0)
    s2 = x.var(axis=0, ddof=1)
    np.testing.assert_allclose(st["var_theta_se"], np.sqrt((m4 - (n - 3) / (n - 1) * s2**2) / n))
    np.testing.assert_allclose(st["p_uplift"], uplift[used].mean(axis=0))
    one = ensemble_statistics(theta, theta_dot, uplift, np.eye(1, 50, 0, dtype=bool)[0])
    assert all(np.all(np.isnan(v)) for v in one.values())


# ---------------------------------------------------------------- overturning and divergence
@pytest.mark.parametrize("model", ["coupled", "condensed"])
def test_all_overturned_gives_nan_statistics_and_says_so(model):
    ds = small_run(model=model, n_samples=4, t_end=4.0, excitation=WhiteNoise(S0=0.5, envelope=ConstantEnvelope()))
    assert ds.attrs["status"] == "all samples overturned"
    assert int(ds.n_overturned) == 4 and int(ds.n_used) == 0 and int(ds.n_diverged) == 0
    assert np.all(np.isnan(ds.var_theta)) and np.all(np.isnan(ds.p_uplift))
    assert np.all(np.isfinite(ds.peak_abs_theta)) and np.all(ds.peak_abs_theta > SLENDERNESS)
    assert np.all(ds.peak_abs_theta < SLENDERNESS + 0.05)                       # stopped at overturning


def test_overturned_samples_are_excluded_from_the_statistics():
    ds = small_run(n_samples=12, t_end=20.0, dt=0.1, excitation=WhiteNoise(S0=2.4e-3, envelope=Envelope(4.0, 2.0)))
    n_over = int(ds.n_overturned)
    assert 0 < n_over < 12 and int(ds.n_used) == 12 - n_over and ds.attrs["status"] == "ok"
    assert np.all(np.isfinite(ds.var_theta))
    over = ds.overturned.values
    assert np.all(ds.peak_abs_theta.values[over] > SLENDERNESS)
    assert np.all(ds.peak_abs_theta.values[~over] <= SLENDERNESS)
    # the statistics of the survivors are bounded by their own peaks
    assert float(ds.var_theta.max()) <= float((ds.peak_abs_theta.values[~over] ** 2).max())


def test_overturning_and_exceedance_probabilities_count_the_samples():
    """p_overturn and p_exceed of the dataset against a direct count of its own per-sample flags and peaks
    (overturned samples exceed every threshold)."""
    ds = small_run(n_samples=12, t_end=20.0, dt=0.1, excitation=WhiteNoise(S0=2.4e-3, envelope=Envelope(4.0, 2.0)),
                   thresholds=[0.2 * SLENDERNESS, 0.6 * SLENDERNESS])
    over, peaks = ds.overturned.values, ds.peak_abs_theta.values
    assert 0 < over.sum() < 12 and float(ds.p_overturn) == over.sum() / 12
    for j, a in enumerate(ds.threshold.values):
        assert float(ds.p_exceed[j]) == np.sum(over | (peaks > a)) / 12
    assert ds.p_exceed.dims == ("threshold",) and ds.threshold.attrs["units"] == "rad"
    assert ds.p_overturn_se.attrs["units"] == "1" and 0 < float(ds.p_overturn_se) < 0.2
    assert "p_exceed" not in small_run() and "p_overturn" in small_run()


def test_diverged_samples_are_flagged_not_fatal():
    ds = small_run(n_samples=3, max_steps=50)
    assert ds.attrs["status"] == "all samples diverged"
    assert ds.diverged.values.all() and int(ds.n_used) == 0
    assert "step budget" in ds.attrs["diverged_reasons"]
    assert np.all(np.isfinite(ds.peak_abs_theta))


def test_flight_then_landing_and_overlong_flight():
    """Dropped from 1 mm above the bed: free fall (flight, F = M = 0), impact, settling."""
    t_out = np.linspace(0.0, 1.0, 21)
    z_st = rest_indentation(BLOCK, HC)
    outs, flags = _run_kernel(kern.MODEL_COUPLED, np.zeros(1100), t_out, HC, [0.0, 0.0, -1e-3, 0.0])
    assert flags[1][0] == kern.STATUS_OK
    t_fall = math.sqrt(2e-3 / BLOCK.g)                                      # ~14 ms in the air
    assert outs[2][0][1] == pytest.approx(z_st, rel=1e-2)                   # landed by 50 ms
    np.testing.assert_allclose(outs[2][0][4:], z_st, rtol=1e-9)             # settled by 0.2 s
    assert np.all(outs[0][0] == 0.0)                                        # a level drop does not rock
    outs, flags = _run_kernel(kern.MODEL_COUPLED, np.zeros(1100), t_out, HC, [0.0, 0.0, -1e-3, 0.0],
                              max_flight_time=0.5 * t_fall)
    assert flags[1][0] == kern.STATUS_DIVERGED and flags[2][0] == kern.REASON_LONG_FLIGHT
    assert np.all(np.isnan(outs[0][0][1:]))


def test_progress_bar(capsys):
    small_run(n_samples=4, chunk_size=2, progress=True)
    assert "monte_carlo[coupled]" in capsys.readouterr().err
    small_run(n_samples=4, chunk_size=2, progress=False)
    assert capsys.readouterr().err == ""


# ---------------------------------------------------------------- statistical checks (slow)
# The stationary linear regime of every Monte Carlo model: tests/verification/test_linear_regime.py.


@pytest.mark.slow
def test_linear_regime_matches_the_lyapunov_solution():
    """Under a modulated input (no closed form) the condensed model follows the moment equations."""
    foundation = Foundation(k=2.89e7, lam=8.95e8, eps=0.0)
    excitation = WhiteNoise(S0=1e-6, envelope=Envelope(4.0, 2.0))
    ref = linearize(BLOCK, foundation, excitation, t_end=20.0, dt=0.05)
    ds = monte_carlo(BLOCK, foundation, excitation, n_samples=1000, model="condensed", seed=12, progress=False)
    at = dict(t=[2.0, 3.0, 5.0, 8.0], method="nearest")
    mc_var, se = ds.var_theta.sel(**at).values, ds.var_theta_se.sel(**at).values
    assert np.all(np.abs(mc_var - ref.var_theta.sel(**at).values) < 3 * se)


@pytest.mark.slow
@pytest.mark.parametrize("model", ["coupled", "condensed"])
def test_halving_the_step_changes_the_peak_variance_much_less_than_its_standard_error(model):
    """rtol / 32 halves the steps of the 5th-order pair; a case with strong uplift (paper case 3)."""
    foundation = Foundation(k=2.89e7, lam=8.95e8, eps=-6e5)
    excitation = WhiteNoise(S0=5e-4, envelope=Envelope(4.0, 2.0))
    kw = dict(n_samples=1000, model=model, seed=5, progress=False)
    coarse = monte_carlo(BLOCK, foundation, excitation, **kw)
    fine = monte_carlo(BLOCK, foundation, excitation, rtol=coarse.attrs["rtol"] / 32, **kw)
    assert fine.attrs["dt_integration_mean"] < 0.6 * coarse.attrs["dt_integration_mean"]
    assert float(coarse.p_uplift.max()) > 0.5                                  # a strongly nonlinear case
    assert int(coarse.n_overturned) == int(fine.n_overturned)
    for name in ("var_theta", "var_theta_dot"):
        i = int(np.argmax(coarse[name].values))
        change = abs(float(fine[name].max()) - float(coarse[name][i]))
        assert change < 0.1 * float(coarse[name + "_se"][i]), (name, change, float(coarse[name + "_se"][i]))


# ---------------------------------------------------------------- cubic condensation
from screening.core.condensation import cubic  # noqa: E402


@pytest.mark.parametrize("kwargs, name", [
    (dict(condensation="exact"), "condensation"), (dict(condensation=None), "condensation"),
    (dict(model="coupled", condensation="cubic"), "condensation"),
    (dict(model="condensed", condensation="cubic", foundation=Foundation(k=2.89e7, lam=8.95e8, eps=-1e8)),
     "foundation.eps"),
])
def test_bad_condensation_raises_before_any_work(no_work, kwargs, name):
    args = dict(n_samples=10**12, model="condensed", seed=0)
    args.update(kwargs)
    foundation = args.pop("foundation", HC)
    with pytest.raises(ValueError, match=f"'{name}'"):
        monte_carlo(BLOCK, foundation, WHITE, **args)


def test_cubic_condensed_run_records_its_condensation():
    ds = small_run(model="condensed", condensation="cubic")
    paper = small_run(model="condensed", condensation="paper")
    assert ds.attrs["condensation"] == "cubic" and paper.attrs["condensation"] == "paper"
    assert float(ds["theta_ul"]) == cubic.uplift_threshold(BLOCK, HC)
    assert ds.attrs["C1"] == pytest.approx(cubic.damping_at_rest(BLOCK, HC), rel=1e-15)
    assert ds.attrs["theta_capacity"] == math.inf and "condensation" not in small_run().attrs
    assert not np.allclose(ds.var_theta.values[1:], paper.var_theta.values[1:], rtol=1e-3, atol=0.0)


def test_cubic_condensed_run_with_eps_zero_is_the_paper_run():
    bed = Foundation(k=2.89e7, lam=8.95e8, eps=0.0)
    strong = WhiteNoise(S0=2.4e-3, envelope=Envelope(4.0, 2.0))
    # the two C, K agree to rounding: at a tight tolerance the runs differ by integration error only
    # (~3e-6 relative here; 7e-4 at the default rtol: the strongly nonlinear samples amplify it)
    cub = small_run(model="condensed", condensation="cubic", foundation=bed, excitation=strong, t_end=4.0, rtol=1e-10)
    paper = small_run(model="condensed", condensation="paper", foundation=bed, excitation=strong, t_end=4.0,
                      rtol=1e-10)
    assert float(paper.p_uplift.max()) > 0.3
    for name in ("var_theta", "var_theta_dot"):
        np.testing.assert_allclose(cub[name].values, paper[name].values, rtol=1e-4,
                                   atol=1e-9 * float(paper[name].max()))


def test_samples_beyond_the_capacity_angle_are_flagged_diverged():
    bed = Foundation(k=2.89e7, lam=8.95e8, eps=-2e7)
    cap = cubic.capacity_angle(BLOCK, bed)
    t_out = np.linspace(0.0, 0.01, 3)
    outs, flags = _run_kernel(kern.MODEL_CONDENSED, np.zeros(200), t_out, bed, [1.01 * cap, 0.0, 0.0, 0.0],
                              condensation="cubic")
    peak, status, reason = flags[0], flags[1], flags[2]
    assert status[0] == kern.STATUS_DIVERGED and reason[0] == kern.REASON_NO_EQUILIBRIUM
    assert peak[0] > cap
    ok, ok_flags = _run_kernel(kern.MODEL_CONDENSED, np.zeros(200), t_out, bed, [0.9 * cap, 0.0, 0.0, 0.0],
                               condensation="cubic")
    assert ok_flags[1][0] == kern.STATUS_OK
    ds = small_run(model="condensed", condensation="cubic", foundation=bed,
                   excitation=WhiteNoise(S0=5e-4, envelope=Envelope(4.0, 2.0)), t_end=3.0)
    assert int(ds.n_diverged) > 0 and "capacity angle" in ds.attrs["diverged_reasons"]
    assert np.all(ds.peak_abs_theta.values[ds.diverged.values] > cap)


def test_cubic_linear_regime_matches_the_cubic_lyapunov_solution():
    """Hardening bed, tiny input: the cubic condensed MCS follows the cubic SL (not the paper's)."""
    from screening.analysis.linearization import linearize
    excitation = WhiteNoise(S0=1e-6, envelope=Envelope(4.0, 2.0))
    ref = linearize(BLOCK, HC, excitation, t_end=8.0, dt=0.05, condensation="cubic")
    ds = monte_carlo(BLOCK, HC, excitation, n_samples=1000, model="condensed", condensation="cubic", t_end=8.0,
                     seed=12, progress=False)
    at = dict(t=[2.0, 3.0, 5.0, 8.0], method="nearest")
    mc_var, se = ds.var_theta.sel(**at).values, ds.var_theta_se.sel(**at).values
    assert np.all(np.abs(mc_var - ref.var_theta.sel(**at).values) < 3 * se)


def test_auto_takes_exact_full_contact_steps_only_on_stiff_beds_under_a_banded_input():
    """``integrator="auto"``: ``"exact"`` where ``w_v dt_grid >= EXACT_CONTACT_MIN`` under a band-limited input;
    the explicit pair on a soft bed and on the idealized input (its runs, and the paper's goldens, unchanged)."""
    from screening.core.excitations.kanai_tajimi import KanaiTajimi
    from screening.solvers.montecarlo import EXACT_CONTACT_MIN, sample_setup
    from screening.solvers.synthesis import vertical_frequency

    statue = Block(m=600.0, b=0.2, h=0.8)
    chosen = {}
    for k in (1e8, 1e11):
        for band in (25.0, None):
            bed = Foundation(k=k, lam=30 * k)
            run = sample_setup(statue, bed, KanaiTajimi(S0=3e-3, omega_g=15.6, zeta_g=0.6, band_limit_hz=band), 8)
            chosen[k, band] = (run.opts["integrator"], vertical_frequency(statue, bed) * run.read_plan.dt)
    assert chosen[1e11, 25.0][0] == "exact" and chosen[1e11, 25.0][1] >= EXACT_CONTACT_MIN
    assert chosen[1e8, 25.0][0] == "dopri" and chosen[1e8, 25.0][1] < EXACT_CONTACT_MIN
    assert chosen[1e11, None][0] == chosen[1e8, None][0] == "dopri"
    bed = Foundation(k=1e11, lam=3e12)
    forced = sample_setup(statue, bed, KanaiTajimi(S0=3e-3, omega_g=15.6, zeta_g=0.6), 8, integrator="dopri")
    assert forced.opts["integrator"] == "dopri"
