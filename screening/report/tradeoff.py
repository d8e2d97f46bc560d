"""Speed–accuracy trade study: stochastic linearization (SL) vs Monte Carlo (condensed, coupled).

SL (~1 ms per point), condensed Monte Carlo on the same SDOF (eq. 22 of [mitseas2026]: isolates SL's
*linearization* error) and coupled Monte Carlo (eqs. 7–8: the judge; condensed vs coupled, same samples,
is the *condensation* error).  :func:`run_tradeoff` measures, over a study's grid
(:func:`~screening.applications.tradeoff_study.parse_tradeoff_study`), every method's error against
coupled Monte Carlo with its standard error and cost, writes ``<stem>.nc``, ``.md``, ``.csv`` and two
figures, and derives SL's validity rules (:mod:`screening.applications.metrics`).  Monte Carlo statistics
are over the survivors; the overturned fraction is reported.  ``docs/validation.md#speed-accuracy-trade``.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from screening.core import laws
from screening.applications.metrics import compare, peak_with_se, relative_difference, time_averaged_relative_error
from screening.analysis.target_intensity import calibrate_intensity
from screening.applications.tradeoff_study import (COMPARISONS, MCS_MODELS, METHODS, QUANTITIES, TradeoffStudy,
                                                   load_tradeoff_study)
from screening.report.tradeoff_files import from_file_layout, output_paths, write_reports
from screening.core.status import flag_attributes, PointStatus
from screening.solvers.schema import apply_schema, cf, declare, PARAMETERS
from screening.solvers.moments import solve_moments
from screening.solvers.montecarlo import monte_carlo
from screening.solvers.timegrid import output_times
from screening.sweep.config import StudyError, build_models

__all__ = []


# ============================================================================ model set-up
@dataclass(frozen=True)
class Point:
    """One grid point of the trade study."""

    name: str
    family: str
    kind: str
    omega_g: float
    zeta_g: float
    eps: float
    S0: float
    target: float
    index: int


def _build_points(study, progress=None):
    """Expand the families into :class:`Point`s (calibrating intensities given as targets)."""
    t_out = output_times(study.t_end, study.dt)
    points = []
    for f, fam in enumerate(study.families):
        for eps in fam.eps:
            for i in range(fam.n_intensities):
                if fam.S0 is not None:
                    S0, target = fam.S0[i], float("nan")
                else:
                    target = fam.target_peak_p_uplift[i]
                    block, bed, _ = build_models(fam.case, {"eps": eps, "S0": 1.0})   # S0: excitation only
                    try:
                        S0 = calibrate_intensity(
                            block, bed, lambda s: build_models(fam.case, {"eps": eps, "S0": s})[2], target, t_out,
                            rtol=study.sl["calibration_rtol"], condensation=study.condensation)
                    except ValueError as err:
                        raise StudyError(f"{study.source}: family[{f}].target_peak_p_uplift[{i}]: family "
                                         f"'{fam.name}', eps = {eps:g}: {err}") from None
                label = f"p{target:g}" if fam.S0 is None else f"S0={S0:.3g}"
                points.append(Point(name=f"{fam.name} eps={eps:g} {label}", family=fam.name, kind=fam.kind,
                                    omega_g=fam.omega_g, zeta_g=fam.zeta_g, eps=float(eps), S0=float(S0),
                                    target=float(target), index=i))
                if progress:
                    progress(f"point {len(points)}: {points[-1].name}: S0 = {S0:.3g} m2 s-3")
    return points


def _point_models(study, points):
    """``(block, foundation, excitation)`` of a :class:`Point`, or of a list of points of one family
    (array fields, for batched calls)."""
    if isinstance(points, Point):
        return build_models(study.family(points.family).case, {"eps": points.eps, "S0": points.S0})
    return build_models(study.family(points[0].family).case, {"eps": np.array([p.eps for p in points]),
                                                               "S0": np.array([p.S0 for p in points])})


# ============================================================================ measurements
def time_call(fn, repeats=1):
    """Call ``fn`` ``repeats`` times and time it.

    Returns ``(result, seconds)``: ``result`` the result of the last call; ``seconds`` median wall time per
    call [s].
    """
    times = []
    result = None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return result, float(np.median(times))


def _solve_sl(study, models, t_out, rtol=None, h_max=None, repeats=1):
    """SL of ``models`` via :func:`~screening.solvers.moments.solve_moments`; ``(result dict, seconds)``."""
    rtol = study.sl["rtol"] if rtol is None else rtol
    return time_call(lambda: solve_moments(*models, t_out, rtol=rtol, h_max=h_max,
                                           condensation=study.condensation), repeats)


def _run_sl(study, point, t_out, rtol=None, h_max=None, repeats=1):
    """SL at one point; ``(result dict, seconds)``."""
    return _solve_sl(study, _point_models(study, point), t_out, rtol, h_max, repeats)


def _run_mcs(study, point, model, n_samples, rtol_factor=1.0):
    """Monte Carlo at one point: ``(dataset, wall seconds)`` (same seed for both models)."""
    block, bed, exc = _point_models(study, point)
    numerics = {"rtol": rtol_factor * study.mcs[f"rtol_{model}"]}
    for key in ("h_max", "chunk_size"):
        if key in study.mcs:
            numerics[key] = study.mcs[key]
    return time_call(lambda: monte_carlo(block, bed, exc, n_samples=n_samples, model=model, t_end=study.t_end,
                                         dt=study.dt, seed=study.mcs["seed"], progress=False,
                                         condensation=study.condensation.name, **numerics))


def _warm_up(study):
    """Compile (or load from cache) the SL and MCS kernels so that no timing includes it."""
    fam = study.families[0]
    pt = Point("warm-up", fam.name, fam.kind, fam.omega_g, fam.zeta_g, fam.eps[0], 1e-6, float("nan"), 0)
    block, bed, exc = _point_models(study, pt)
    t_short = output_times(study.dt * 4, study.dt)
    solve_moments(block, bed, exc, t_short, condensation=study.condensation)
    for model in MCS_MODELS:
        monte_carlo(block, bed, exc, n_samples=2, model=model, t_end=study.dt * 4, dt=study.dt, progress=False,
                    condensation=study.condensation)


def set_threads(n):
    """Limit numba to ``n`` threads (cost per core).

    Returns: the previous setting.
    """
    import numba
    previous = numba.get_num_threads()
    numba.set_num_threads(min(int(n), numba.config.NUMBA_NUM_THREADS))
    return previous


def _history(ds, name):
    return np.asarray(ds[name].values, dtype=float)


def _log(progress, msg):
    if progress:
        progress(msg)


def _stderr(msg):
    print(f"[tradeoff] {msg}", file=sys.stderr, flush=True)


def _measure_grid(study, points, t_out, progress=None):
    """SL and both MCS models at every point: histories, costs and overturning counts."""
    n, nt = len(points), t_out.size
    hist = {q: np.full((len(METHODS), n, nt), np.nan) for q in QUANTITIES}
    se = {q: np.full((len(METHODS), n, nt), np.nan) for q in QUANTITIES}
    p_upl = np.full((len(METHODS), n, nt), np.nan)
    cost = np.full((len(METHODS), n), np.nan)
    n_over = np.zeros((len(MCS_MODELS), n), dtype=np.int32)
    n_div = np.zeros((len(MCS_MODELS), n), dtype=np.int32)
    n_used = np.zeros((len(MCS_MODELS), n), dtype=np.int32)
    sl_status = np.zeros(n, dtype=np.int8)
    sl_peak_p = np.full(n, np.nan)
    sl_margin = np.full(n, np.nan)
    sl_min_k = np.full(n, np.nan)
    sl_k0 = np.full(n, np.nan)
    mcs_runs = {}
    for j, pt in enumerate(points):
        res, sec = _run_sl(study, pt, t_out, repeats=study.sl["timing_repeats"])
        hist["var_theta"][0, j] = res["var_theta"]
        hist["var_theta_dot"][0, j] = res["var_theta_dot"]
        p_upl[0, j] = res["p_uplift"]
        cost[0, j] = sec
        sl_status[j] = res["status"]
        sl_peak_p[j] = res["peak_p_uplift"]
        sl_min_k[j] = res["min_k_eq"]
        sl_k0[j] = res["k_eq"][0]
        sl_margin[j] = res["min_k_eq"] / res["k_eq"][0]
        for m, model in enumerate(MCS_MODELS):
            ds, sec = _run_mcs(study, pt, model, study.mcs["samples"])
            mcs_runs[(j, model)] = (ds, sec)
            row = 1 + m
            for q in QUANTITIES:
                hist[q][row, j] = _history(ds, q)
                se[q][row, j] = _history(ds, q + "_se")
            p_upl[row, j] = _history(ds, "p_uplift")
            cost[row, j] = sec
            n_over[m, j], n_div[m, j], n_used[m, j] = int(ds.n_overturned), int(ds.n_diverged), int(ds.n_used)
            _log(progress, f"{j + 1}/{n} {pt.name}: {model} MCS {sec:.1f} s, overturned {n_over[m, j]}")
    return {"hist": hist, "se": se, "p_uplift": p_upl, "cost": cost, "n_overturned": n_over,
            "n_diverged": n_div, "n_used": n_used, "sl_status": sl_status, "sl_peak_p_uplift": sl_peak_p,
            "sl_margin": sl_margin, "sl_min_k_eq": sl_min_k, "sl_k_eq0": sl_k0, "mcs_runs": mcs_runs}


def _grid_errors(grid, t_out):
    """:func:`compare` for every comparison x quantity x point; dict of arrays."""
    n = grid["cost"].shape[1]
    keys = ("peak_estimate", "peak_reference", "peak_rel_error", "peak_rel_se", "peak_significant",
            "time_avg_rel_error", "time_avg_rel_se", "time_avg_significant")
    out = {k: np.full((len(COMPARISONS), len(QUANTITIES), n), np.nan) for k in keys}
    for c, (est, ref) in enumerate(COMPARISONS.values()):
        ie, ir = METHODS.index(est), METHODS.index(ref)
        for iq, q in enumerate(QUANTITIES):
            for j in range(n):
                e_se = None if est == "sl" else grid["se"][q][ie, j]
                r = compare(grid["hist"][q][ie, j], grid["hist"][q][ir, j], t_out, est_se=e_se,
                            ref_se=grid["se"][q][ir, j])
                for k in keys:
                    out[k][c, iq, j] = r[k]
    for k in ("peak_significant", "time_avg_significant"):
        out[k] = out[k].astype(bool)
    return out


def _measure_convergence(study, points, grid, t_out, progress=None):
    """MCS peak variance, SE and cost vs sample count and vs rtol factor at the chosen points."""
    cv = study.convergence
    idx = [next(j for j, p in enumerate(points) if (p.family, p.eps, p.index) == key) for key in cv["points"]]
    models, ns, factors = cv["models"], cv["samples"], cv["rtol_factors"]
    shape_n = (len(idx), len(models), len(ns))
    shape_f = (len(idx), len(models), len(factors))
    out = {name: np.full(shape_n, np.nan) for name in ("peak", "peak_se", "peak_dot", "peak_dot_se", "cost")}
    out["n_overturned"] = np.zeros(shape_n, dtype=np.int32)
    out.update({f"tol_{name}": np.full(shape_f, np.nan) for name in ("peak", "peak_se", "peak_dot", "cost")})
    out["tol_n_overturned"] = np.zeros(shape_f, dtype=np.int32)
    for a, j in enumerate(idx):
        for b, model in enumerate(models):
            runs = {}
            for c, n_s in enumerate(ns):
                if n_s == study.mcs["samples"]:
                    ds, sec = grid["mcs_runs"][(j, model)]
                else:
                    ds, sec = _run_mcs(study, points[j], model, n_s)
                    _log(progress, f"convergence {points[j].name}: {model} n={n_s} {sec:.1f} s")
                runs[n_s] = (ds, sec)
                out["peak"][a, b, c], out["peak_se"][a, b, c] = peak_with_se(_history(ds, "var_theta"),
                                                                             _history(ds, "var_theta_se"))
                out["peak_dot"][a, b, c], out["peak_dot_se"][a, b, c] = peak_with_se(
                    _history(ds, "var_theta_dot"), _history(ds, "var_theta_dot_se"))
                out["cost"][a, b, c] = sec
                out["n_overturned"][a, b, c] = int(ds.n_overturned)
            for c, f in enumerate(factors):
                if f == 1.0:
                    ds, sec = runs[cv["rtol_samples"]]
                else:
                    ds, sec = _run_mcs(study, points[j], model, cv["rtol_samples"], rtol_factor=f)
                    _log(progress, f"tolerance {points[j].name}: {model} rtol x {f:g} {sec:.1f} s")
                out["tol_peak"][a, b, c], out["tol_peak_se"][a, b, c] = peak_with_se(
                    _history(ds, "var_theta"), _history(ds, "var_theta_se"))
                out["tol_peak_dot"][a, b, c] = peak_with_se(_history(ds, "var_theta_dot"))[0]
                out["tol_cost"][a, b, c] = sec
                out["tol_n_overturned"][a, b, c] = int(ds.n_overturned)
    out["point_index"] = np.array(idx)
    # SL at the same points (for biases against the largest-sample reference)
    out["sl_peak"] = np.array([peak_with_se(grid["hist"]["var_theta"][0, j])[0] for j in idx])
    return out


def _measure_sl_numerics(study, points, t_out):
    """SL numerical error (vs ``reference_rtol``) and cost per point over rtol and h_max settings."""
    ref = [_run_sl(study, p, t_out, rtol=study.sl["reference_rtol"])[0] for p in points]
    settings = [("rtol", r, None) for r in study.sl["rtol_sweep"]]
    settings += [("h_max", study.sl["rtol"], h) for h in study.sl["h_max_sweep"]]
    n = len(points)
    out = {k: np.full((len(settings), n), np.nan) for k in ("cost", "peak_err", "time_avg_err", "n_steps")}
    for s, (_, rtol, h_max) in enumerate(settings):
        for j, p in enumerate(points):
            res, sec = _run_sl(study, p, t_out, rtol=rtol, h_max=h_max, repeats=study.sl["timing_repeats"])
            out["cost"][s, j] = sec
            out["n_steps"][s, j] = res["n_steps"]
            out["peak_err"][s, j] = relative_difference(res["peak_var_theta"], ref[j]["peak_var_theta"])
            out["time_avg_err"][s, j] = time_averaged_relative_error(res["var_theta"], ref[j]["var_theta"], t_out)
    # the whole grid in batched calls, one per family (per-point cost of the batched form)
    fam_costs = []
    for fam in study.families:
        sel = [p for p in points if p.family == fam.name]
        _, sec = _solve_sl(study, _point_models(study, sel), t_out, repeats=study.sl["timing_repeats"])
        fam_costs.append((sec, len(sel)))
    batched = sum(s for s, _ in fam_costs) / sum(k for _, k in fam_costs)
    out["settings"] = settings
    out["batched_cost"] = batched
    return out


# ============================================================================ dataset
#: The variables and label coordinates of the speed-accuracy trade study's dataset, declared here.
TRADEOFF = declare("tradeoff", {
    # coordinates
    "approach": {"long_name": "method: sl (stochastic linearization), condensed_mcs, coupled_mcs"},
    "mcs_model": {"long_name": "Monte Carlo model"},
    "comparison": {"long_name": "estimate_vs_reference", "note": "relative errors are estimate/reference - 1"},
    "quantity": {"long_name": "response variance compared"},
    "point": {"long_name": "grid point index"},
    "point_name": {"long_name": "grid point label"},
    "family": {"long_name": "excitation family"},
    "excitation_kind": {"long_name": "excitation kind"},
    "omega_g": {**PARAMETERS["omega_g"], "note": "NaN for white noise"},
    "zeta_g": {**PARAMETERS["zeta_g"], "note": "NaN for white noise"},
    "target_peak_p_uplift": cf("1", "target SL peak uplift probability used to calibrate S0"),
    "rep_point_index": {"long_name": "grid point index of a representative point"},
    "rep_point_name": {"long_name": "label"},
    "cv_model": {"long_name": "Monte Carlo model (convergence study)"},
    "n_samples": cf("1", "Monte Carlo sample count"),
    "rtol_factor": cf("1", "factor on the model's default MCS rtol"),
    "sl_setting": {"long_name": "SL numerics setting"},
    "sl_setting_kind": {"long_name": "which parameter is varied"},
    "sl_rtol": cf("1", "SL relative tolerance"),
    "sl_h_max": cf("s", "SL largest step (NaN: default t_end/20)"),
    # histories and per-point results of each method
    "var_theta": cf("rad2", "var_theta by each method", note="MCS: over surviving samples"),
    "var_theta_dot": cf("rad2 s-2", "var_theta_dot by each method", note="MCS: over surviving samples"),
    "var_theta_se": cf("rad2", "Monte Carlo standard error of var_theta (NaN for sl)"),
    "var_theta_dot_se": cf("rad2 s-2", "Monte Carlo standard error of var_theta_dot (NaN for sl)"),
    "p_uplift": cf("1", "uplift probability / occupancy"),
    "cost": cf("s", "wall time per point on one core"),
    "n_overturned": cf("1", "overturned samples"),
    "n_diverged": cf("1", "diverged samples"),
    "n_used": cf("1", "samples in the statistics (survivors)"),
    "overturned_fraction": cf("1", "fraction of samples that overturned (statistics are over survivors)"),
    "sl_status": flag_attributes([s for s in PointStatus if s >= PointStatus.ok], "SL solver status"),
    "sl_peak_p_uplift": cf("1", "SL peak uplift probability (eq. 58)"),
    "sl_min_k_eq": cf("N m rad-1", "SL minimum equivalent stiffness"),
    "sl_k_eq0": cf("N m rad-1", "SL equivalent stiffness at t = 0"),
    "k_eq_margin": cf("1", "min_k_eq / k_eq(t=0) from SL"),
    "peak_var_theta": cf("rad2", "peak over time of var_theta"),
    "peak_var_theta_se": cf("rad2", "Monte Carlo standard error of peak_var_theta (at the peak time; 0 for sl)"),
    "peak_var_theta_dot": cf("rad2 s-2", "peak over time of var_theta_dot"),
    "peak_var_theta_dot_se": cf("rad2 s-2", "Monte Carlo standard error of peak_var_theta_dot (at the peak time; "
                                            "0 for sl)"),
    # errors of each comparison
    "peak_rel_error": cf("1", "relative error of the peak: max_t estimate / max_t reference - 1"),
    "peak_rel_se": cf("1", "standard error of the peak difference / reference peak (quadrature for MCS vs MCS)"),
    "peak_significant": cf("1", "1 if |peak difference| > 2 SE"),
    "time_avg_rel_error": cf("1", "int |estimate - reference| dt / int |reference| dt where both are defined"),
    "time_avg_rel_se": cf("1", "int SE dt / int |reference| dt (noise floor of time_avg_rel_error)"),
    "time_avg_significant": cf("1", "1 if time_avg_rel_error > 2 time_avg_rel_se"),
    # Monte Carlo vs sample count and tolerance
    "cv_peak_var_theta": cf("rad2", "MCS peak var_theta vs sample count"),
    "cv_peak_var_theta_se": cf("rad2", "its standard error"),
    "cv_peak_var_theta_dot": cf("rad2 s-2", "MCS peak var_theta_dot"),
    "cv_peak_var_theta_dot_se": cf("rad2 s-2", "its standard error"),
    "cv_cost": cf("s", "wall time per point, one core"),
    "cv_n_overturned": cf("1", "overturned samples"),
    "cv_deviation_vs_reference": cf("1", "peak var_theta / peak at the largest sample count (same model) - 1",
                                    note="nested samples (same seed): the reference contains the smaller ensembles"),
    "cv_rel_se": cf("1", "relative standard error of peak var_theta"),
    "cv_sl_peak_var_theta": cf("rad2", "SL peak var_theta"),
    "tol_peak_var_theta": cf("rad2", "MCS peak var_theta vs tolerance (same seed)"),
    "tol_peak_var_theta_se": cf("rad2", "its standard error"),
    "tol_cost": cf("s", "wall time per point, one core"),
    "tol_n_overturned": cf("1", "overturned samples"),
    "tol_change_vs_tightest": cf("1", "peak var_theta / peak at the tightest tolerance - 1 (paired samples)"),
    # SL numerics
    "sl_cost": cf("s", "SL wall time per point (single-point call, median)"),
    "sl_n_steps": cf("1", "SL solver steps"),
    "sl_numerical_peak_error": cf("1", "SL peak var_theta / tight-tolerance reference - 1"),
    "sl_numerical_time_avg_error": cf("1", "SL time-averaged relative error of var_theta vs the tight-tolerance "
                                           "reference"),
    "sl_batched_cost": cf("s", "SL wall time per point in batched calls"),
})


def _build_dataset(study, points, t_out, grid, errors, conv, numerics, wall_time):
    """Assemble every measurement in one labelled :class:`xarray.Dataset`; units and long names
    from :data:`TRADEOFF`."""
    cv = study.convergence
    settings = numerics["settings"]
    reps = conv["point_index"]
    coords = {
        "t": t_out, "approach": list(METHODS), "mcs_model": list(MCS_MODELS), "comparison": list(COMPARISONS),
        "quantity": list(QUANTITIES), "point": np.arange(len(points)),
        "point_name": ("point", [p.name for p in points]),
        "family": ("point", [p.family for p in points]),
        "excitation_kind": ("point", [p.kind for p in points]),
        **{name: ("point", [getattr(p, name) for p in points]) for name in ("eps", "S0", "omega_g", "zeta_g")},
        "target_peak_p_uplift": ("point", [p.target for p in points]),
        "rep_point_index": ("rep_point", reps.astype(np.int32)),
        "rep_point_name": ("rep_point", [points[j].name for j in reps]),
        "cv_model": list(cv["models"]), "n_samples": np.array(cv["samples"], dtype=np.int32),
        "rtol_factor": np.array(cv["rtol_factors"]),
        "sl_setting": np.arange(len(settings)),
        "sl_setting_kind": ("sl_setting", [s[0] for s in settings]),
        "sl_rtol": ("sl_setting", [s[1] for s in settings]),
        "sl_h_max": ("sl_setting", [np.nan if s[2] is None else s[2] for s in settings]),
    }
    apt, ap, mp = ("approach", "point", "t"), ("approach", "point"), ("mcs_model", "point")
    dv = {}
    for q in QUANTITIES:
        dv[q] = (apt, grid["hist"][q])
        dv[q + "_se"] = (apt, grid["se"][q])
    dv["p_uplift"] = (apt, grid["p_uplift"])
    dv["cost"] = (ap, grid["cost"], {
        "note": f"sl: median of {study.sl['timing_repeats']} single-point solve_moments calls; "
                f"MCS: one monte_carlo call with {study.mcs['samples']} samples, "
                f"{study.mcs['threads']} numba thread(s)"})
    for name in ("n_overturned", "n_diverged", "n_used"):
        dv[name] = (mp, grid[name])
    dv["overturned_fraction"] = (mp, grid["n_overturned"] / study.mcs["samples"])
    dv["sl_status"] = ("point", grid["sl_status"])
    for name, key in (("sl_peak_p_uplift", "sl_peak_p_uplift"), ("sl_min_k_eq", "sl_min_k_eq"),
                      ("sl_k_eq0", "sl_k_eq0"), ("k_eq_margin", "sl_margin")):
        dv[name] = ("point", grid[key])
    for k in ("peak_rel_error", "peak_rel_se", "peak_significant", "time_avg_rel_error", "time_avg_rel_se",
              "time_avg_significant"):
        val = errors[k].astype(np.int8) if errors[k].dtype == bool else errors[k]
        dv[k] = (("comparison", "quantity", "point"), val)
    for q in QUANTITIES:
        peak, se = peak_with_se(grid["hist"][q], grid["se"][q])
        dv[f"peak_{q}"], dv[f"peak_{q}_se"] = (ap, peak), (ap, se)
    # convergence sub-study
    rn, rf = ("rep_point", "cv_model", "n_samples"), ("rep_point", "cv_model", "rtol_factor")
    for name, key in (("cv_peak_var_theta", "peak"), ("cv_peak_var_theta_se", "peak_se"),
                      ("cv_peak_var_theta_dot", "peak_dot"), ("cv_peak_var_theta_dot_se", "peak_dot_se"),
                      ("cv_cost", "cost"), ("cv_n_overturned", "n_overturned")):
        dv[name] = (rn, conv[key])
    dv["cv_deviation_vs_reference"] = (rn, conv["peak"] / conv["peak"][:, :, -1:] - 1.0)
    dv["cv_rel_se"] = (rn, conv["peak_se"] / conv["peak"])
    dv["tol_peak_var_theta"] = (rf, conv["tol_peak"], {"note": f"{cv['rtol_samples']} samples"})
    for name, key in (("tol_peak_var_theta_se", "tol_peak_se"), ("tol_cost", "tol_cost"),
                      ("tol_n_overturned", "tol_n_overturned")):
        dv[name] = (rf, conv[key])
    dv["tol_change_vs_tightest"] = (rf, conv["tol_peak"] / conv["tol_peak"][:, :, :1] - 1.0)
    dv["cv_sl_peak_var_theta"] = ("rep_point", conv["sl_peak"])
    # SL numerics
    sp = ("sl_setting", "point")
    dv["sl_cost"] = (sp, numerics["cost"])
    dv["sl_n_steps"] = (sp, numerics["n_steps"])
    dv["sl_numerical_peak_error"] = (sp, numerics["peak_err"],
                                     {"note": f"reference: rtol {study.sl['reference_rtol']:g}"})
    dv["sl_numerical_time_avg_error"] = (sp, numerics["time_avg_err"])
    dv["sl_batched_cost"] = ((), numerics["batched_cost"])
    case = study.families[0].case          # block, bed and envelope are common to every family
    p = case.params
    attrs = {
        "title": study.title,
        "study_file": study.source,
        "study_toml": study.text,
        "mcs_samples": study.mcs["samples"], "mcs_seed": study.mcs["seed"], "mcs_threads": study.mcs["threads"],
        "mcs_rtol_coupled": study.mcs["rtol_coupled"], "mcs_rtol_condensed": study.mcs["rtol_condensed"],
        "sl_rtol_default": study.sl["rtol"],
        "tol_samples": cv["rtol_samples"],
        "statistics_note": "Monte Carlo moments are over surviving samples (neither overturned nor diverged); "
                           "condensed and coupled MCS use the same input samples (same seed)",
        "significance": "peak: |diff| > 2 SE; time-averaged: error > 2 x noise floor",
        "rule_metric": study.rule["metric"], "rule_quantity": study.rule["quantity"],
        "wall_time_s": float(wall_time),
        "block_m": p["m"], "block_b": p["b"], "block_h": p["h"],
        "foundation_contact": case.contact, "foundation_k": p["k"],
        "envelope_T1": p["T1"], "envelope_T2": p["T2"],
        "t_end": study.t_end, "dt": study.dt,
    }
    damping = laws.get(case.contact).parameter
    attrs[f"foundation_{damping}"] = p[damping]
    return apply_schema(xr.Dataset(dv, coords=coords, attrs=attrs), table=TRADEOFF)


# ============================================================================ runner
def _stem(study):
    return Path(study.source).stem if study.source != "<string>" else "tradeoff"


def _study(study_path):
    return study_path if isinstance(study_path, TradeoffStudy) else load_tradeoff_study(study_path)


def run_tradeoff(study_path, out_dir="outputs", progress=_stderr):
    """Run the whole trade study of ``study_path`` and write its outputs into ``out_dir``.

    ``study_path`` may also be a parsed :class:`TradeoffStudy`; outputs are named after the
    study file's stem (see :func:`~screening.report.tradeoff_files.output_paths`).  ``progress``
    is a callable taking one line of text (default: stderr) or None.  Returns
    ``(dataset, paths, rules)``: the dataset of :func:`_build_dataset`, the dict of written files
    and the rules of :func:`~screening.applications.metrics.derive_rules`.  A bad study file raises
    :class:`~screening.sweep.config.StudyError` before any work, and nothing is written.

    Returns: ``(dataset, paths, rules)``: the :class:`xarray.Dataset` of every measurement (SI units in its
    ``units`` attributes), ``{kind: pathlib.Path}`` of the written files and the rules.

    Notes
    -----
    The errors of the linearization [1] and of the condensed Monte Carlo against the coupled one,
    with their Monte Carlo standard errors [rubinstein2017]; what the shipped study found: ``docs/validation.md``.
    """
    study = _study(study_path)
    start = time.perf_counter()
    previous = set_threads(study.mcs["threads"])
    try:
        _warm_up(study)
        t_out = output_times(study.t_end, study.dt)
        points = _build_points(study, progress)
        grid = _measure_grid(study, points, t_out, progress)
        errors = _grid_errors(grid, t_out)
        conv = _measure_convergence(study, points, grid, t_out, progress)
        numerics = _measure_sl_numerics(study, points, t_out)
    finally:
        set_threads(previous)
    ds = _build_dataset(study, points, t_out, grid, errors, conv, numerics, time.perf_counter() - start)
    paths, rules = write_reports(study, ds, out_dir, _stem(study))
    return ds, paths, rules


def rerender_reports(study_path, out_dir="outputs"):
    """Re-derive the rules and rewrite the markdown, CSV and plots from the saved ``<out_dir>/<stem>.nc``,
    without recomputing (e.g. after changing ``[rule]``).

    Returns ``(dataset, paths, rules)`` as :func:`run_tradeoff` (``paths`` without the netCDF).  Raises
    :class:`~screening.sweep.config.StudyError` for a bad study file and ``FileNotFoundError``
    when the study has not been run into ``out_dir``.

    Returns: ``(dataset, paths, rules)``.
    """
    study = _study(study_path)
    nc = output_paths(out_dir, _stem(study))["nc"]
    if not nc.exists():
        raise FileNotFoundError(f"{nc} does not exist (run the study first)")
    with xr.open_dataset(nc) as saved:
        ds = from_file_layout(saved.load())
    paths, rules = write_reports(study, ds, out_dir, _stem(study), write_nc=False)
    del paths["nc"]
    return ds, paths, rules
