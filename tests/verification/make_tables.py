"""Write ``tables/linear_regime.csv``: the stationary rocking variances of a block that never uplifts.

Independent of the package (numpy and scipy only): in full contact every model reduces to the linear
oscillator ``I theta'' + C theta' + K theta = -m h a(t)`` about the centre of the base, with

* ``I = m (b^2 + h^2) / 3 + m h^2`` (uniform rectangle, half-width ``b``, height of the centre ``h``);
* ``K = (2/3) k b^3 - m g h`` (the bed's rocking stiffness less the overturning moment of gravity);
* ``C = (2/3) c b^3`` (Winkler dashpot ``c``) or ``lam b^2 m g / (3 k)`` (Hunt-Crossley ``lam``).

Under a stationary input of two-sided PSD ``S(w)`` [m^2 s^-3]::

    var_theta     = int |H(w)|^2 S(w) dw,      |H|^2 = (m h)^2 / ((K - I w^2)^2 + (C w)^2)
    var_theta_dot = int w^2 |H(w)|^2 S(w) dw

over the whole line; white noise has the closed form ``pi S0 (m h)^2 / (C K)`` (and ``K / I`` times it),
the other rows are integrated by ``scipy.integrate.quad``.  ``S`` is white or Kanai-Tajimi
(``S0 (wg^4 + 4 zg^2 wg^2 w^2) / ((wg^2 - w^2)^2 + 4 zg^2 wg^2 w^2)``), times the ground band's
Butterworth gain ``1 / (1 + (w / (2 pi f))^8)`` where ``band_limit_hz = f`` is given.

Run ``python tests/verification/make_tables.py`` to rewrite the table (the tests require that it
reproduces the checked-in file).
"""

from __future__ import annotations

import csv
import math
import sys
from pathlib import Path

from scipy.integrate import quad

G = 9.81
TABLE = Path(__file__).with_name("tables") / "linear_regime.csv"
FIELDS = ("case", "m", "b", "h", "k", "lam", "c", "kind", "S0", "omega_g", "zeta_g", "band_limit_hz",
          "var_theta", "var_theta_dot", "how")
#: The rows: a light block on the paper's soft Hunt-Crossley bed, a statue on a stiff one, a Winkler bed;
#: white and Kanai-Tajimi input, idealized or at the ground's 25 Hz band.  Every intensity keeps the
#: standard deviation of theta below 0.15 of the uplift angle, so no model leaves full contact.
ROWS = [
    dict(case="soft_white", m=8.67, b=0.035, h=0.21, k=2.89e7, lam=8.95e8, c=0.0, kind="white", S0=1e-6),
    dict(case="soft_kanai_tajimi", m=8.67, b=0.035, h=0.21, k=2.89e7, lam=8.95e8, c=0.0, kind="kanai_tajimi",
         S0=2e-5, omega_g=10.0, zeta_g=0.4),
    dict(case="soft_kanai_tajimi_band", m=8.67, b=0.035, h=0.21, k=2.89e7, lam=8.95e8, c=0.0,
         kind="kanai_tajimi", S0=2e-5, omega_g=10.0, zeta_g=0.4, band_limit_hz=25.0),
    dict(case="statue_white_band", m=1200.0, b=0.25, h=0.9, k=1e9, lam=1e10, c=0.0, kind="white", S0=1e-6,
         band_limit_hz=25.0),
    dict(case="winkler_white", m=8.67, b=0.035, h=0.21, k=2.89e7, lam=0.0, c=2e5, kind="white", S0=1e-6),
]


def oscillator(row):
    """``(I, C, K, m h)`` of the row's block in full contact (SI)."""
    m, b, h, k = row["m"], row["b"], row["h"], row["k"]
    inertia = m * (b * b + h * h) / 3.0 + m * h * h
    damping = 2.0 / 3.0 * row["c"] * b**3 + row["lam"] * b * b * m * G / (3.0 * k)
    return inertia, damping, 2.0 / 3.0 * k * b**3 - m * G * h, m * h


def psd(row, w):
    """The row's two-sided input PSD [m^2 s^-3] at ``w`` [rad/s]."""
    s = row["S0"]
    if row["kind"] == "kanai_tajimi":
        wg, zg = row["omega_g"], row["zeta_g"]
        s *= (wg**4 + 4 * zg**2 * wg**2 * w * w) / ((wg**2 - w * w) ** 2 + 4 * zg**2 * wg**2 * w * w)
    if row.get("band_limit_hz"):
        s /= 1.0 + (w / (2.0 * math.pi * row["band_limit_hz"])) ** 8
    return s


def moments(row):
    """``(var_theta, var_theta_dot, how)`` of the row (closed form for idealized white noise)."""
    inertia, damping, stiffness, lever = oscillator(row)
    if row["kind"] == "white" and not row.get("band_limit_hz"):
        var = math.pi * row["S0"] * lever**2 / (damping * stiffness)
        return var, var * stiffness / inertia, "closed form"

    def h2(w):
        return lever**2 / ((stiffness - inertia * w * w) ** 2 + (damping * w) ** 2) * psd(row, w)

    w0 = math.sqrt(stiffness / inertia)
    breaks = [w0] + [v for v in (row.get("omega_g"), 2 * math.pi * row.get("band_limit_hz", 0) or None) if v]
    top = 1e3 * max(breaks)
    opts = dict(points=sorted(breaks), limit=1000, epsrel=1e-11, epsabs=0.0)
    var = 2.0 * (quad(h2, 0.0, top, **opts)[0] + quad(h2, top, math.inf, epsrel=1e-11, epsabs=0.0)[0])
    var_dot = 2.0 * (quad(lambda w: w * w * h2(w), 0.0, top, **opts)[0]
                     + quad(lambda w: w * w * h2(w), top, math.inf, epsrel=1e-11, epsabs=0.0)[0])
    return var, var_dot, "quadrature"


def rows():
    """The table's rows as dicts of strings (what the CSV holds)."""
    out = []
    for row in ROWS:
        var, var_dot, how = moments(row)
        full = {"omega_g": "", "zeta_g": "", "band_limit_hz": "", **row}
        full.update(var_theta=repr(var), var_theta_dot=repr(var_dot), how=how)
        out.append({f: str(full[f]) for f in FIELDS})
    return out


if __name__ == "__main__":
    with open(TABLE, "w", newline="") as fh:
        writer = csv.DictWriter(fh, FIELDS)
        writer.writeheader()
        writer.writerows(rows())
    sys.stdout.write(f"wrote {TABLE}\n")
