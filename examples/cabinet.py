"""Cabinet on hardening elastomeric pads, from Python: the bed from materials, the study run, its fragility.

Run from the repository's root::

    .venv/bin/python examples/cabinet.py             # writes outputs/cabinet.nc and its figures

The pads' ``k`` and ``lam`` in ``cabinet.toml`` are the numbers :func:`bed` prints; ``eps`` comes from
the pads' backbone test (:func:`screening.analysis.beds.fit_backbone` fits ``F = k z (1 + eps z^2)``).
"""

import sys
from pathlib import Path

import xarray as xr

from screening import beds
from screening.sweep.study import load_study
from screening.sweep.run import run_sweep
from screening.core.status import FitFlag

HERE = Path(__file__).resolve().parent


def bed(m=400.0, b=0.3, depth=0.6, thickness=0.020):
    """``(k [N m-2], lam [N s m-3])`` of bonded pads (E 4 MPa, shape factor 8, vertical damping 10 %)."""
    modulus = beds.pad_compression_modulus(E=4e6, shape_factor=8, kappa=0.75)
    k = beds.layer_stiffness(modulus, thickness=thickness, depth=depth)
    return k, beds.lam_from_vertical_damping(k, m=m, b=b, zeta_v=0.10)


def main(study=HERE / "cabinet.toml", out="outputs/cabinet.nc"):
    """Run the study in this process and return the fragility curves over PGA (``[fragility]`` thresholds)."""
    k, lam = bed()
    print(f"pads: k = {k:.3g} N m-2, lam = {lam:.3g} N s m-3")
    run_sweep(load_study(study), out, workers=0)
    with xr.open_dataset(out) as result:
        curves = result.rocking.fragility_curve(0.3, dim="pga", relative_to="slenderness").load()
        trust = result["sl_trust"].load()
    flag = FitFlag(int(curves["fit_flag"]))
    fit = (f"median PGA {float(curves['fit_median']):.3g} m s-2, beta {float(curves['beta']):.3g}"
           if flag == FitFlag.ok else f"no fit ({flag.name}: {flag.meaning})")
    print(f"P(|theta| > 0.3 atan(b/h)): {fit}; {int(curves['fit_n_unvouched'])} point(s) left out (nothing vouches "
          f"for them); linearization {trust.attrs['flag_meanings']}: "
          + ", ".join(str(int((trust == v).sum())) for v in trust.attrs["flag_values"]))
    return curves


if __name__ == "__main__":
    main(*sys.argv[1:])
