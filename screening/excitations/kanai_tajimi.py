"""Modulated Kanai–Tajimi noise (paper eqs. 47–50): white noise through the soil filter
``u'' + 2 zeta_g omega_g u' + omega_g^2 u = -w``, output ``a = -(omega_g^2 u + 2 zeta_g omega_g u')``."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np

from screening.excitations.base import Excitation, Filter, Parameter
from screening.excitations.registry import register
from screening.model.excitation import ConstantEnvelope, Envelope

__all__ = ["kanai_tajimi_filter", "kanai_tajimi_psd", "KanaiTajimi", "kanai_tajimi_stationary_moments",
           "stationary_filter_moments_jit"]


def kanai_tajimi_filter(omega_g, zeta_g):
    """State-space matrices of the Kanai–Tajimi filter, states ``(u [m s], u' [m])`` for ``w`` in m/s^2.

    ``A = [[0, 1], [-omega_g^2, -2 zeta_g omega_g]]``, ``B = [0, -1]``,
    ``C = [-omega_g^2, -2 zeta_g omega_g]``, ``D = 0`` (eqs. 47–49; the output is
    ``a = u'' + w = -(omega_g^2 u + 2 zeta_g omega_g u')``).  ``omega_g`` [rad/s], ``zeta_g`` [1],
    arrays broadcast (leading axes of the result).
    """
    wg, zg = np.broadcast_arrays(np.asarray(omega_g, dtype=float), np.asarray(zeta_g, dtype=float))
    zero, one = np.zeros_like(wg), np.ones_like(wg)
    w2, two_zw = wg * wg, 2.0 * zg * wg
    A = np.stack([np.stack([zero, one], -1), np.stack([-w2, -two_zw], -1)], -2)
    return Filter(A, np.stack([zero, -one], -1), np.stack([-w2, -two_zw], -1), zero)


def kanai_tajimi_psd(omega, S0, omega_g, zeta_g):
    """Two-sided Kanai–Tajimi PSD [m^2/s^3] at ``omega`` [rad/s] (eq. 50):
    ``S0 (omega_g^4 + 4 zeta_g^2 omega_g^2 omega^2) / ((omega^2 - omega_g^2)^2 + 4 zeta_g^2 omega_g^2 omega^2)``."""
    w = np.asarray(omega, dtype=float)
    wg, zg = omega_g, zeta_g
    num = wg**4 + 4.0 * zg**2 * wg**2 * w**2
    den = (w**2 - wg**2) ** 2 + 4.0 * zg**2 * wg**2 * w**2
    return S0 * num / den


@register
@dataclass(frozen=True)
class KanaiTajimi(Excitation):
    """Modulated Kanai–Tajimi noise ``q(t) z(t)`` (eqs. 47–50).

    Parameters
    ----------
    S0 : two-sided PSD level of the white noise driving the filter [m^2/s^3], > 0.
    omega_g : filter (soil) natural frequency [rad/s], > 0.
    zeta_g : filter damping ratio [1], > 0.
    envelope : modulating function.
    """

    S0: float
    omega_g: float
    zeta_g: float
    envelope: Envelope | ConstantEnvelope = field(default_factory=Envelope)

    kind = "kanai_tajimi"
    description = "modulated Kanai-Tajimi noise (eqs. 47-50)"
    parameters = {"omega_g": Parameter("rad s-1", "Kanai-Tajimi filter frequency"),
                  "zeta_g": Parameter("1", "Kanai-Tajimi filter damping ratio")}


    def filter(self):
        return kanai_tajimi_filter(self.omega_g, self.zeta_g)

    def psd(self, omega):
        """Two-sided PSD of the filter output ``z`` [m^2/s^3] at ``omega`` [rad/s] (eq. 50)."""
        return kanai_tajimi_psd(omega, self.S0, self.omega_g, self.zeta_g)

    def stationary_covariance(self):
        """Stationary covariance of ``(u, u')``: :func:`kanai_tajimi_stationary_moments` on the diagonal."""
        var_u, var_u_dot, _ = kanai_tajimi_stationary_moments(self.S0, self.omega_g, self.zeta_g)
        var_u, var_u_dot = np.broadcast_arrays(var_u, var_u_dot)
        zero = np.zeros_like(var_u)
        return np.stack([np.stack([var_u, zero], -1), np.stack([zero, var_u_dot], -1)], -2)


def kanai_tajimi_stationary_moments(S0, omega_g, zeta_g):
    """Stationary variances of the Kanai–Tajimi filter (eq. 49) under ``2 pi S0`` white noise.

    Returns ``(var_u [m^2], var_u_dot [m^2/s^2], var_z [m^2/s^4])``: ``var_u = pi S0 / (2 zeta_g omega_g^3)``,
    ``var_u_dot = pi S0 / (2 zeta_g omega_g)`` and the output
    ``var_z = pi S0 omega_g (1 + 4 zeta_g^2) / (2 zeta_g)``; ``cov(u, u_dot) = 0``.
    ``S0`` [m^2/s^3], ``omega_g`` [rad/s], ``zeta_g`` [1].
    """
    var_u = np.pi * S0 / (2.0 * zeta_g * omega_g**3)
    var_u_dot = np.pi * S0 / (2.0 * zeta_g * omega_g)
    var_z = np.pi * S0 * omega_g * (1.0 + 4.0 * zeta_g**2) / (2.0 * zeta_g)
    return var_u, var_u_dot, var_z


@numba.njit(cache=True)
def stationary_filter_moments_jit(S0, omega_g, zeta_g):
    """Compiled twin of :func:`kanai_tajimi_stationary_moments`: ``(var_u [m^2], var_u_dot [m^2/s^2])``."""
    return math.pi * S0 / (2.0 * zeta_g * omega_g**3), math.pi * S0 / (2.0 * zeta_g * omega_g)
