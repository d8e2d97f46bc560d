"""How far a recomputation may sit from the numbers the package ships, from the solver's own accuracy.

Tests that compare a fresh linearization with stored numbers (the error atlas's features and peak variances)
must allow what the integration itself does not resolve: another machine (other SIMD width, other rounding)
takes other adaptive steps.  This prints, for the atlas points those tests use, the largest change of each
feature and of the peak variance between the product's tolerance (rtol 1e-8) and a solve at rtol 1e-11, and
the change against the stored value on this machine.

    PYTHONPATH=. python benchmarks/stored_numbers_accuracy.py
"""

from importlib import resources

import numpy as np
import xarray as xr

from screening.applications import atlas
from screening.analysis import error_model as em
from screening.analysis.linearization import linearize

POINTS = 8
RTOLS = (1e-8, 1e-11)


def main():
    with resources.as_file(resources.files("screening.data") / "error_atlas.nc") as path:
        shipped = xr.load_dataset(path)
    g = atlas.groups_of(shipped["u"].values)
    x_atlas = em.atlas_features(shipped, "paper")
    stored_var = shipped["sl_peak_var_theta"].sel(condensation="paper").values
    feature_err, feature_stored, var_err, var_stored = [], [], [], []
    for i in range(shipped.sizes["point"]):
        if len(var_err) == POINTS:
            break
        if not np.isfinite(shipped["S0"].values[i]) or shipped["sl_status"].values[i, 0] != 0:
            continue
        block, foundation, shape, timing = atlas.physical_point(g, i)
        excitation = atlas.make_excitation(shape, timing, float(shipped["S0"].values[i]))
        runs = [linearize(block, foundation, excitation, t_end=timing["t_end"], dt=timing["dt"],
                          condensation="paper", rtol=rtol) for rtol in RTOLS]
        x = [em.dataset_features(ds)[0][0] for ds in runs]
        v = [float(ds.peak_var_theta) for ds in runs]
        feature_err.append(np.abs(x[0] - x[1]))
        feature_stored.append(np.abs(x[0] - x_atlas[i]))
        var_err.append(abs(v[0] / v[1] - 1.0))
        var_stored.append(abs(v[0] / stored_var[i] - 1.0))
    print(f"{len(var_err)} atlas points, paper condensation, rtol {RTOLS[0]:g} against {RTOLS[1]:g}")
    print(f"{'feature':<18} {'integration error':>18} {'vs stored here':>15}")
    for name, a, b in zip(em.FEATURES, np.max(feature_err, axis=0), np.max(feature_stored, axis=0)):
        print(f"{name:<18} {a:18.2e} {b:15.2e}")
    print(f"{'peak_var_theta':<18} {max(var_err):18.2e} {max(var_stored):15.2e}   (relative)")


if __name__ == "__main__":
    main()
