"""Marble statue on a mortar bed: the bed from materials, a PGA sweep, a fragility curve over PGA.

Run from the repository's root::

    .venv/bin/python examples/statue.py              # writes outputs/statue.nc, its figures and
                                                     # outputs/statue_fragility.{nc,png}

The bed's ``k`` and ``lam`` in ``statue.toml`` are the numbers :func:`bed` prints.
"""

import sys
from pathlib import Path

import xarray as xr

from screening import beds
from screening.cli import main as screening

HERE = Path(__file__).resolve().parent


def bed(m=1200.0, b=0.25, depth=0.5, thickness=0.010):
    """``(k [N m-2], lam [N s m-3])`` of a lime-cement mortar joint (E 5 GPa, nu 0.2, vertical damping 3 %)."""
    k = beds.layer_stiffness(beds.oedometric_modulus(E=5e9, nu=0.2), thickness=thickness, depth=depth)
    return k, beds.lam_from_vertical_damping(k, m=m, b=b, zeta_v=0.03)


def main(study=HERE / "statue.toml", out="outputs/statue.nc"):
    """Run the study, then the fragility of ``|theta| > 0.3 atan(b/h)`` over PGA; returns its dataset."""
    k, lam = bed()
    print(f"bed: k = {k:.3g} N m-2, lam = {lam:.3g} N s m-3")
    if screening(["run", str(study), "--out", str(out)]) != 0:
        raise SystemExit("the study did not run")
    curve = str(Path(out).with_name(Path(out).stem + "_fragility.nc"))
    if screening(["fragility", str(out), "--threshold", "0.3", "--relative-to", "slenderness", "--dim", "pga",
                  "--out", curve]) != 0:
        raise SystemExit("no fragility curve")
    with xr.open_dataset(curve) as fragility:
        fragility.load()
    print(f"median PGA {float(fragility['fit_median']):.3g} m s-2, beta {float(fragility['beta']):.3g}")
    return fragility


if __name__ == "__main__":
    main(*sys.argv[1:])
