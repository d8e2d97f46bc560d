"""Modulated Kanai–Tajimi noise (paper eqs. 47–50): white noise through the soil filter
``u'' + 2 zeta_g omega_g u' + omega_g^2 u = -w``, output ``a = -(omega_g^2 u + 2 zeta_g omega_g u')``."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np

from screening.core.excitations.base import GROUND_BAND_LIMIT_HZ, Excitation, Filter, Parameter
from screening.core.model.excitation import ConstantEnvelope, Envelope

__all__ = ["KanaiTajimi"]


def kanai_tajimi_filter(omega_g, zeta_g):
    """State-space matrices of the Kanai–Tajimi filter, states ``(u [m s], u' [m])`` for ``w`` in m s-2.

    Parameters
    ----------
    omega_g, zeta_g : array_like
        Filter (soil) natural frequency [rad s-1] and damping ratio [1], both > 0.

    Returns
    -------
    screening.core.excitations.Filter
        ``(A, B, C, D)`` [.., 2, 2], [.., 2], [.., 2], [..]: arrays broadcast into the leading axes.

    Notes
    -----
    ``A = [[0, 1], [-omega_g^2, -2 zeta_g omega_g]]``, ``B = [0, -1]``,
    ``C = [-omega_g^2, -2 zeta_g omega_g]``, ``D = 0``: eqs. (47)-(49) in [1], the output
    ``a = u'' + w = -(omega_g^2 u + 2 zeta_g omega_g u')`` (eq. (48) with the sign of ``w`` folded into ``B``).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    wg, zg = np.broadcast_arrays(np.asarray(omega_g, dtype=float), np.asarray(zeta_g, dtype=float))
    zero, one = np.zeros_like(wg), np.ones_like(wg)
    w2, two_zw = wg * wg, 2.0 * zg * wg
    A = np.stack([np.stack([zero, one], -1), np.stack([-w2, -two_zw], -1)], -2)
    return Filter(A, np.stack([zero, -one], -1), np.stack([-w2, -two_zw], -1), zero)


def kanai_tajimi_psd(omega, S0, omega_g, zeta_g):
    """Two-sided Kanai–Tajimi power spectral density [m2 s-3].

    Parameters
    ----------
    omega : array_like
        Circular frequency [rad s-1].
    S0, omega_g, zeta_g : array_like
        As in :func:`kanai_tajimi_stationary_moments`.

    Returns
    -------
    numpy.ndarray
        ``S(omega)`` [m2 s-3], broadcast over the arguments.

    Notes
    -----
    ``S0 (omega_g^4 + 4 zeta_g^2 omega_g^2 omega^2) / ((omega^2 - omega_g^2)^2 + 4 zeta_g^2 omega_g^2
    omega^2)``, eq. (50) in [1]; the transfer function of :func:`kanai_tajimi_filter`.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    w = np.asarray(omega, dtype=float)
    wg, zg = omega_g, zeta_g
    with np.errstate(invalid="ignore", divide="ignore", under="ignore"):   # beyond float range: NaN, flagged
        num = wg**4 + 4.0 * zg**2 * wg**2 * w**2
        den = (w**2 - wg**2) ** 2 + 4.0 * zg**2 * wg**2 * w**2
        return S0 * num / den


@dataclass(frozen=True)
class KanaiTajimi(Excitation):
    """Modulated Kanai–Tajimi noise ``q(t) z(t)`` (eqs. 47–50).

    Parameters
    ----------
    S0 : two-sided PSD level of the white noise driving the filter [m^2/s^3], > 0.
    omega_g : filter (soil) natural frequency [rad/s], > 0.
    zeta_g : filter damping ratio [1], > 0.
    envelope : modulating function.
    band_limit_hz : corner of the band's low-pass [Hz] (:class:`~screening.core.excitations.Excitation`), None: none.
    """

    S0: float
    omega_g: float
    zeta_g: float
    envelope: Envelope | ConstantEnvelope = field(default_factory=Envelope)
    band_limit_hz: float | None = GROUND_BAND_LIMIT_HZ

    kind = "kanai_tajimi"
    description = "modulated Kanai-Tajimi noise (eqs. 47-50)"
    parameters = {"omega_g": Parameter("rad s-1", "Kanai-Tajimi filter frequency"),
                  "zeta_g": Parameter("1", "Kanai-Tajimi filter damping ratio")}


    def shaping_filter(self):
        return kanai_tajimi_filter(self.omega_g, self.zeta_g)

    def shaping_psd(self, omega):
        """Two-sided PSD of the filter output ``z`` [m^2/s^3] at ``omega`` [rad/s] (eq. 50), without the band."""
        return kanai_tajimi_psd(omega, self.S0, self.omega_g, self.zeta_g)

    def stationary_covariance(self):
        """Stationary covariance of ``(u, u')``: :func:`kanai_tajimi_stationary_moments` on the diagonal (with a
        band, of every filter state: the base class's)."""
        if self.band_limit_hz is not None:
            return super().stationary_covariance()
        var_u, var_u_dot, _ = kanai_tajimi_stationary_moments(self.S0, self.omega_g, self.zeta_g)
        var_u, var_u_dot = np.broadcast_arrays(var_u, var_u_dot)
        zero = np.zeros_like(var_u)
        return np.stack([np.stack([var_u, zero], -1), np.stack([zero, var_u_dot], -1)], -2)


def kanai_tajimi_stationary_moments(S0, omega_g, zeta_g):
    """Stationary variances of the Kanai–Tajimi filter under white noise of PSD ``S0``.

    Parameters
    ----------
    S0 : array_like
        Two-sided PSD level of the driving white noise [m2 s-3].
    omega_g : array_like
        Filter (soil) natural frequency [rad s-1], > 0.
    zeta_g : array_like
        Filter damping ratio [1], > 0.

    Returns
    -------
    var_u : numpy.ndarray or float
        ``pi S0 / (2 zeta_g omega_g^3)`` [m2].
    var_u_dot : numpy.ndarray or float
        ``pi S0 / (2 zeta_g omega_g)`` [m2 s-2].
    var_z : numpy.ndarray or float
        Variance of the output ``pi S0 omega_g (1 + 4 zeta_g^2) / (2 zeta_g)`` [m2 s-4]; ``cov(u, u') = 0``.

    Notes
    -----
    The stationary solution of the filter block of the Lyapunov equation (eqs. (49) and (51) in [1])
    under ``E[w(t) w(s)] = 2 pi S0 delta(t - s)``; ``var_z`` is the integral of eq. (50) over all
    frequencies.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    """
    var_u = np.pi * S0 / (2.0 * zeta_g * omega_g**3)
    var_u_dot = np.pi * S0 / (2.0 * zeta_g * omega_g)
    var_z = np.pi * S0 * omega_g * (1.0 + 4.0 * zeta_g**2) / (2.0 * zeta_g)
    return var_u, var_u_dot, var_z


@numba.njit(cache=True)
def stationary_filter_moments_jit(S0, omega_g, zeta_g):
    """Compiled twin of :func:`kanai_tajimi_stationary_moments` (the filter's two variances, ``var_u`` [m2] and
    ``var_u_dot`` [m2 s-2])."""
    return math.pi * S0 / (2.0 * zeta_g * omega_g**3), math.pi * S0 / (2.0 * zeta_g * omega_g)
