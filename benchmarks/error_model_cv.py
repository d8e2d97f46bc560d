"""Grouped cross-validation of the error model (:mod:`screening.analysis.error_model`) on the error atlas.

Run::

    nice -n 5 env PYTHONPATH=$PWD .venv/bin/python benchmarks/error_model_cv.py \
        [--atlas screening/data/error_atlas.nc] [--folds 0] [--coverage 0.9] [--variance-only] [--experiments]

For each condensation, the atlas families are split into folds (``--folds 0``: one family per fold,
leave-one-family-out); the model is fitted on the other folds and predicts the held-out points.
Printed per condensation and error:

* ``coverage``: fraction of held-out points whose measured error lies in the 90 % interval (goal >= 88 %);
  ``coverage_se``: the same with the interval widened by the point's own Monte Carlo standard error
  (the measured error carries the reference's sampling noise, the true one does not);
* ``cov raw``: the same against the *unclipped* measured error, with an interval end that reaches the fit's
  clip (a factor 4) open (:func:`~screening.analysis.error_model.open_ended`, as the product reports it);
  ``open``: the fraction of such intervals;
* ``width``: median interval width; for the variance as a fraction of the corrected estimate,
  ``exp(high) - exp(low)`` over ``exp(estimate)`` (goal <= 25 %); for probabilities in probability;
* ``trusted`` / ``bad trusted``: held-out points the model labels trusted (:func:`~screening.analysis.error_model.
  trust_from_interval`) and, of those, how many have a measured |SL / MC - 1| > 25 % beyond 2 MC standard
  errors (goal: none);
* the cost of a prediction per point [us] and the best condensation by region of peak p_uplift.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_ATLAS = ROOT / "screening" / "data" / "error_atlas.nc"


def main(argv=None):
    import xarray as xr

    from screening.analysis import error_model as em

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--atlas", default=str(DEFAULT_ATLAS))
    ap.add_argument("--folds", type=int, default=0)
    ap.add_argument("--coverage", type=float, default=0.9)
    ap.add_argument("--variance-only", action="store_true", help="skip the exceedance probabilities (5 x faster)")
    ap.add_argument("--experiments", action="store_true",
                    help="only the feature-set comparison: the shipped per-regime model against one feature set "
                         "everywhere (the eleven features shipped before, thirteen, the indicators with and without e)")
    args = ap.parse_args(argv)
    ds = xr.load_dataset(args.atlas)
    if args.experiments:
        feature_experiments(ds)
        return 0
    groups = ds["family"].values
    print(f"atlas: {ds.sizes['point']} points, {len(np.unique(groups))} families, "
          f"{ds.attrs.get('cpu_hours', float('nan'))} CPU h; folds: "
          f"{args.folds or 'one family each'}")
    print(f"{'condensation':13s} {'error':16s} {'n':>5s} {'coverage':>8s} {'cov+se':>7s} {'cov raw':>7s} {'open':>5s} "
          f"{'width':>7s} {'trusted':>7s} {'bad':>4s}")
    best = {}
    n_used = np.maximum(ds["mc_n_samples"].values - ds["mc_n_diverged"].values, 1)
    p_over = ds["mc_n_overturned"].values / n_used
    for cond in ds["condensation"].values:
        x = em.atlas_features(ds, cond)
        t = em.targets(ds, cond)
        y, y_se = np.clip(t["log_var_ratio"], -em.LOG_CLIP, em.LOG_CLIP), t["log_var_ratio_se"]
        est, lo, hi = em.grouped_cross_validation(x, y, groups, args.folds, args.coverage, clip=em.LOG_CLIP)
        ok = np.isfinite(y) & np.isfinite(est)
        inside = (y >= lo) & (y <= hi)
        inside_se = (y >= lo - y_se) & (y <= hi + y_se)
        _, lo_o, hi_o = em.open_ended(est, lo, hi)
        y_raw = t["log_var_ratio"]
        inside_raw = (y_raw >= lo_o) & (y_raw <= hi_o)
        is_open = ~np.isfinite(lo_o) | ~np.isfinite(hi_o)
        width = (np.exp(hi) - np.exp(lo)) / np.exp(est)
        trusted = em.trust_from_interval(lo, hi) == 0
        rel = np.exp(y) - 1
        bad = trusted & ok & (np.abs(rel) - 2 * y_se * np.exp(y) > em.TRUSTED_ERROR)
        def row(label, sel):
            print(f"{cond:13s} {label:16s} {sel.sum():5d} {inside[sel].mean():8.3f} {inside_se[sel].mean():7.3f} "
                  f"{inside_raw[sel].mean():7.3f} {is_open[sel].mean():5.2f} {np.median(width[sel]):7.3f} "
                  f"{int((trusted & sel).sum()):7d} {int((bad & sel).sum()):4d}")

        row("log var ratio", ok)
        standing = ok & (p_over <= 0.05)
        row("  MC p_over<=5%", standing)
        p_cond = ds["sl_peak_p_uplift"].sel(condensation=cond).values
        row("  and p_up<0.5", standing & (p_cond < 0.5))
        regime = np.searchsorted(np.asarray(em.P_REGIMES), p_cond, side="right")
        for k, label in enumerate(("  p_up<0.2", "  p_up 0.2-0.7", "  p_up>=0.7")):
            row(label, ok & (regime == k))
        # the reference's own sampling error alone: a 90 % interval of the measured error no narrower than
        # 2 sinh(1.645 se) as a fraction of the estimate
        print(f"{cond:13s} {'  MC noise floor':16s} median width from the reference's SE alone "
              f"{np.median(2 * np.sinh(1.6449 * y_se[ok])):.3f} (p_up<0.2 / 0.2-0.7 / >=0.7: " + " / ".join(
                  f"{np.median(2 * np.sinh(1.6449 * y_se[ok & (regime == k)])):.3f}" for k in range(3)) + ")")
        best[cond] = (y, est, ok)
        rule = ds["sl_trust"].sel(condensation=cond).values
        lo_r, hi_r = (ds[n].sel(condensation=cond).values for n in ("sl_error_low", "sl_error_high"))
        rel_true = np.expm1(t["log_var_ratio"])
        has_band = ok & np.isfinite(lo_r)
        in_band = (rel_true >= lo_r) & (rel_true <= hi_r)
        print(f"{cond:13s} {'  shipped rule':16s} trusted {int(((rule == 0) & ok).sum())} (beyond 25 %: "
              f"{int(((rule == 0) & ok & (np.abs(rel_true) - 2 * y_se * np.exp(t['log_var_ratio']) > 0.25)).sum())}), "
              f"check {int(((rule == 1) & ok).sum())}, untrusted {int(((rule == 2) & ok).sum())}; its band covers "
              f"{in_band[has_band].mean() if has_band.any() else float('nan'):.3f} of {int(has_band.sum())}, median "
              f"width {np.median((hi_r - lo_r)[has_band]) if has_band.any() else float('nan'):.3f}")
        for j, level in enumerate(() if args.variance_only else ds["level"].values):
            yp, se = t["p_exceed_diff"][:, j], t["p_exceed_diff_se"][:, j]
            e2, l2, h2 = em.grouped_cross_validation(x, yp, groups, args.folds, args.coverage)
            okp = np.isfinite(yp) & np.isfinite(e2)
            ins = (yp >= l2) & (yp <= h2)
            ins_se = (yp >= l2 - se) & (yp <= h2 + se)
            print(f"{cond:13s} {'p_exceed ' + format(level, 'g') + ' alpha':16s} {okp.sum():5d} {ins[okp].mean():8.3f} "
                  f"{ins_se[okp].mean():7.3f} {np.median((h2 - l2)[okp]):7.3f}")
    # cost of a prediction
    x = em.atlas_features(ds, "paper")
    y = em.targets(ds, "paper")["log_var_ratio"]
    per = prediction_cost(em.fit_error_model(x, y, groups, clip=em.LOG_CLIP), x)
    print(f"error model cost: {per:.1f} us CPU per point (10000 points, {int(np.isfinite(y).sum())} "
          f"atlas rows; the linearization: ~200 us)")
    # best condensation by p_uplift region (measured |log error|)
    p = ds["sl_peak_p_uplift"].sel(condensation="paper").values
    edges = (0.0, 0.05, 0.2, 0.5, 0.8, 0.95, 1.01)
    print("best condensation by the paper linearization's peak p_uplift, points where every condensation and the "
          "reference have a value (median |SL/MC - 1|; fraction within 25 %; n):")
    common = np.logical_and.reduce([ok for _, _, ok in best.values()])
    for a, b in zip(edges[:-1], edges[1:]):
        sel = (p >= a) & (p < b) & common
        cells = []
        for cond, (y, _, _) in best.items():
            rel = np.abs(np.expm1(y[sel]))
            cells.append((np.median(rel) if sel.any() else np.nan, cond, np.mean(rel <= 0.25) if sel.any() else np.nan))
        text = "  ".join(f"{c}: {v:.3f}, {w:.2f}" for v, c, w in cells)
        win = min((c for c in cells if np.isfinite(c[0])), default=(np.nan, "-", 0))[1]
        print(f"  [{a:g}, {b:g}) n={int(sel.sum()):3d}: {text}  -> {win}")
    stopped = {str(cond): int((ds["sl_status"].sel(condensation=cond).values != 0).sum()) for cond in best}
    print(f"linearization stopped (status not ok) at: {stopped} of {ds.sizes['point']} points")
    print_stops(ds, edges)
    return 0


def feature_experiments(ds):
    """Leave one family out (log var ratio) with a feature set per uplift regime: the shipped one
    (:data:`~screening.analysis.error_model.REGIME_FEATURES`) against one set everywhere (the eleven features of
    the model shipped before, the thirteen, the four indicators, the indicators and ``e``); coverage and median
    width per regime and where the reference overturns at most 5 % of its samples, trusted and wrongly trusted
    held-out points per regime, the points near the regimes' edge at 0.2, and the cost of a prediction."""
    from screening.analysis import error_model as em

    groups = ds["family"].values
    n_used = np.maximum(ds["mc_n_samples"].values - ds["mc_n_diverged"].values, 1)
    standing = ds["mc_n_overturned"].values / n_used <= 0.05
    sets = {"before: 11 features": (em.FEATURES[:11],) * em.N_REGIMES, "13 features": (em.FEATURES,) * em.N_REGIMES,
            "4 indicators": (em.FEATURES[:4],) * em.N_REGIMES,
            "indicators + e": (em.LOW_UPLIFT_FEATURES,) * em.N_REGIMES, "shipped (per regime)": em.REGIME_FEATURES}
    for cond in ds["condensation"].values:
        x = em.atlas_features(ds, cond)
        t = em.targets(ds, cond)
        y, y_se = t["log_var_ratio"], t["log_var_ratio_se"]
        yc = np.clip(y, -em.LOG_CLIP, em.LOG_CLIP)
        p = ds["sl_peak_p_uplift"].sel(condensation=cond).values
        regime = np.searchsorted(np.asarray(em.P_REGIMES), p, side="right")
        edge = (p >= 0.15) & (p < 0.25)
        for label, regimes in sets.items():
            est, lo, hi = em.grouped_cross_validation(x, y, groups, clip=em.LOG_CLIP, regimes=regimes)
            ok = np.isfinite(y) & np.isfinite(est)
            width = (np.exp(hi) - np.exp(lo)) / np.exp(est)
            inside = (yc >= lo) & (yc <= hi)
            trusted = (em.trust_from_interval(lo, hi) == 0) & ok
            bad = trusted & (np.abs(np.expm1(yc)) - 2 * y_se * np.exp(yc) > em.TRUSTED_ERROR)
            print(f"{str(cond):13s} {label:21s} n {int(ok.sum())} (" + " / ".join(
                str(int((ok & (regime == k)).sum())) for k in range(3)) + f") coverage {inside[ok].mean():.3f} (" + " / ".join(
                f"{inside[ok & (regime == k)].mean():.3f}" for k in range(3)) + f"), median width "
                f"{np.median(width[ok]):.3f} (" + " / ".join(f"{np.median(width[ok & (regime == k)]):.3f}"
                                                             for k in range(3)) +
                f"; MC overturns <= 5 %: {np.median(width[ok & standing]):.3f}), trusted {int(trusted.sum())} (" +
                " / ".join(str(int((trusted & (regime == k)).sum())) for k in range(3)) +
                f"), beyond 25 %: {int(bad.sum())}; p_uplift 0.15-0.25: n {int((ok & edge).sum())}, coverage "
                f"{inside[ok & edge].mean():.3f}, trusted {int((trusted & edge).sum())}", flush=True)
    x = em.atlas_features(ds, "paper")
    y = em.targets(ds, "paper")["log_var_ratio"]
    for label in ("before: 11 features", "shipped (per regime)"):
        model = em.fit_error_model(x, y, groups, clip=em.LOG_CLIP, regimes=sets[label])
        print(f"error model cost, {label}: {prediction_cost(model, x):.1f} us CPU per point")


def prediction_cost(model, x, n=10_000):
    """CPU time [us] of :func:`~screening.analysis.error_model.interval_trust` per point, over ``n`` queries near
    atlas rows of ``x``."""
    from screening.analysis import error_model as em

    finite = x[np.all(np.isfinite(x), axis=1)]
    rng = np.random.default_rng(0)
    xq = finite[rng.integers(0, len(finite), n)] * (1 + 0.01 * rng.normal(size=(n, x.shape[1])))
    t0 = time.process_time()
    em.interval_trust(model, xq)
    return (time.process_time() - t0) / n * 1e6


def print_stops(ds, edges):
    """Each condensation on every point with a reference, a stop counted as a miss: per bin of the paper
    linearization's peak p_uplift, median |SL/MC - 1| where it runs / fraction of the bin within 25 % /
    stops; and where virtual_work stops but paper runs, how wrong paper is and how often the reference
    overturns."""
    from screening.analysis import error_model as em

    mc = ds["mc_peak_var_theta"].values
    ref = np.isfinite(mc) & (mc > 0) & em.valid_reference(ds)   # one outside its model's validity is none
    conds = [str(c) for c in ds["condensation"].values]
    st = {c: ds["sl_status"].sel(condensation=c).values for c in conds}
    with np.errstate(invalid="ignore", divide="ignore"):
        err = {c: np.abs(ds["sl_peak_var_theta"].sel(condensation=c).values / mc - 1) for c in conds}
    p = ds["sl_peak_p_uplift"].sel(condensation="paper").values
    print(f"every point with a reference ({int(ref.sum())}), a stop counted as a miss:")
    for c in conds:
        ok = ref & (st[c] == 0)
        print(f"  {c:13s} stops {int(np.sum(ref & (st[c] != 0))):4d}, within 25 % {np.sum(err[c][ok] <= 0.25) / ref.sum():.3f}, "
              f"median |SL/MC - 1| where it runs {np.median(err[c][ok]):.3f}")
    print("  peak p_uplift (paper) | n | " + " | ".join(f"{c}: median / within 25 % / stops" for c in conds))
    for a, b in zip(edges[:-1], edges[1:]):
        sel = ref & (p >= a) & (p < b)
        cells = []
        for c in conds:
            e = err[c][sel & (st[c] == 0)]
            cells.append(f"{np.median(e) if e.size else np.nan:.3f} / {np.sum(e <= 0.25) / max(sel.sum(), 1):.2f} / "
                         f"{int(np.sum(sel & (st[c] != 0)))}")
        print(f"  [{a:g}, {b:g}) | {int(sel.sum())} | " + " | ".join(cells))
    n_used = np.maximum(ds["mc_n_samples"].values - ds["mc_n_diverged"].values, 1)
    over = ds["mc_n_overturned"].values / n_used
    for other in conds[1:]:
        sel = ref & (st[other] != 0) & (st["paper"] == 0)
        if sel.any():
            e = err["paper"][sel]
            print(f"  {other} stops, paper runs: {int(sel.sum())} points; paper |SL/MC - 1| median {np.median(e):.3f}, "
                  f"within 25 % {np.mean(e <= 0.25):.3f}, beyond 50 % {np.mean(e > 0.5):.3f}; the reference overturns "
                  f"> 5 % of its samples at {np.mean(over[sel] > 0.05):.3f} of them (median {np.median(over[sel]):.3f})")


if __name__ == "__main__":
    sys.exit(main())
