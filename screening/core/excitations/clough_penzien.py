"""Modulated Clough–Penzien noise: the Kanai–Tajimi output through a second-order high-pass filter.

The Kanai–Tajimi spectrum stays finite at ``omega = 0`` (``S(0) = S0``), which gives ground
displacements and velocities an unbounded variance and biases long-period responses.  Clough and
Penzien (1975) pass the Kanai–Tajimi output ``z`` through a second filter
``v'' + 2 zeta_f omega_f v' + omega_f^2 v = z`` and take ``a = v''``, which removes the low
frequencies (``S ~ omega^4`` near 0)::

    S(omega) = S_KT(omega) omega^4 / ((omega_f^2 - omega^2)^2 + 4 zeta_f^2 omega_f^2 omega^2)

States ``(u, u', v, v')``: ``u'' + 2 zeta_g omega_g u' + omega_g^2 u = -w``,
``z = -(omega_g^2 u + 2 zeta_g omega_g u')``, ``a = z - 2 zeta_f omega_f v' - omega_f^2 v``.

References: Clough, R. W. and Penzien, J. (1975) Dynamics of Structures, McGraw-Hill, New York.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from screening.core.excitations.base import GROUND_BAND_LIMIT_HZ, Excitation, Filter, Parameter
from screening.core.excitations.kanai_tajimi import KanaiTajimi, kanai_tajimi_psd
from screening.core.model.excitation import ConstantEnvelope, Envelope

__all__ = ["CloughPenzien"]


def clough_penzien_filter(omega_g, zeta_g, omega_f, zeta_f):
    """State-space matrices ``(A, B, C, D)`` of the Clough–Penzien filter, states ``(u, u', v, v')``.

    Parameters
    ----------
    omega_g : array_like
        Kanai–Tajimi (soil) filter frequency [rad s-1], > 0.
    zeta_g : array_like
        Kanai–Tajimi filter damping ratio [1], > 0.
    omega_f : array_like
        High-pass filter frequency [rad s-1], > 0.
    zeta_f : array_like
        High-pass filter damping ratio [1], > 0.

    Returns
    -------
    screening.core.excitations.Filter
        ``A`` [.., 4, 4], ``B``, ``C`` [.., 4], ``D`` [..]: arrays broadcast into the leading axes.

    Notes
    -----
    ``A = [[0, 1, 0, 0], [-wg^2, -2 zg wg, 0, 0], [0, 0, 0, 1], [-wg^2, -2 zg wg, -wf^2, -2 zf wf]]``,
    ``B = [0, -1, 0, 0]``, ``C = [-wg^2, -2 zg wg, -wf^2, -2 zf wf]``, ``D = 0``: the Kanai–Tajimi filter
    of eqs. (47)-(49) in [1] followed by the second-order high-pass of [2].

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [clough1975] in the bibliography, ``docs/bibliography.md``.
    """
    wg, zg, wf, zf = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (omega_g, zeta_g, omega_f, zeta_f)))
    zero, one = np.zeros_like(wg), np.ones_like(wg)
    g2, g1, f2, f1 = wg * wg, 2.0 * zg * wg, wf * wf, 2.0 * zf * wf
    rows = [[zero, one, zero, zero], [-g2, -g1, zero, zero], [zero, zero, zero, one], [-g2, -g1, -f2, -f1]]
    A = np.stack([np.stack(r, -1) for r in rows], -2)
    return Filter(A, np.stack([zero, -one, zero, zero], -1), np.stack([-g2, -g1, -f2, -f1], -1), zero)


def clough_penzien_psd(omega, S0, omega_g, zeta_g, omega_f, zeta_f):
    """Two-sided Clough–Penzien power spectral density [m2 s-3].

    Parameters
    ----------
    omega, S0, omega_g, zeta_g : array_like
        As in :func:`~screening.core.excitations.kanai_tajimi.kanai_tajimi_psd`.
    omega_f, zeta_f : array_like
        As in :func:`clough_penzien_filter`.

    Returns
    -------
    numpy.ndarray
        ``S(omega)`` [m2 s-3]: the Kanai–Tajimi PSD times the high-pass, broadcast over the arguments.

    Notes
    -----
    The Kanai–Tajimi PSD (eq. (50) in [1]) times the high-pass ``omega^4 / ((omega_f^2 - omega^2)^2 +
    4 zeta_f^2 omega_f^2 omega^2)`` of [2], which removes the Kanai–Tajimi spectrum's finite value at
    ``omega = 0`` (the cure of its long-period bias).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [clough1975] in the bibliography, ``docs/bibliography.md``.
    """
    w2 = np.asarray(omega, dtype=float) ** 2
    high_pass = w2 * w2 / ((omega_f**2 - w2) ** 2 + 4.0 * zeta_f**2 * omega_f**2 * w2)
    return kanai_tajimi_psd(omega, S0, omega_g, zeta_g) * high_pass


@dataclass(frozen=True)
class CloughPenzien(Excitation):
    """Modulated Clough–Penzien noise ``q(t) a(t)`` (module docstring).

    Parameters
    ----------
    S0 : two-sided PSD level of the white noise driving the filters [m^2/s^3], > 0.
    omega_g, zeta_g : Kanai–Tajimi (soil) filter frequency [rad/s] and damping ratio [1], > 0.
    omega_f, zeta_f : high-pass filter frequency [rad/s] and damping ratio [1], > 0.
    envelope, band_limit_hz : as in :class:`~screening.core.excitations.kanai_tajimi.KanaiTajimi`.
    """

    kind = "clough_penzien"
    description = "modulated Clough-Penzien noise (Kanai-Tajimi and a second-order high-pass)"
    parameters = {**KanaiTajimi.parameters,
                  "omega_f": Parameter("rad s-1", "Clough-Penzien high-pass filter frequency"),
                  "zeta_f": Parameter("1", "Clough-Penzien high-pass filter damping ratio")}

    S0: float
    omega_g: float
    zeta_g: float
    omega_f: float
    zeta_f: float
    envelope: Envelope | ConstantEnvelope = field(default_factory=Envelope)
    band_limit_hz: float | None = GROUND_BAND_LIMIT_HZ


    def shaping_filter(self):
        return clough_penzien_filter(self.omega_g, self.zeta_g, self.omega_f, self.zeta_f)

    def shaping_psd(self, omega):
        """Two-sided PSD of the filtered input [m^2/s^3] at ``omega`` [rad/s]."""
        return clough_penzien_psd(omega, self.S0, self.omega_g, self.zeta_g, self.omega_f, self.zeta_f)
