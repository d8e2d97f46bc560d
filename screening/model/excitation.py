"""Stochastic ground excitation: envelopes, modulated white noise, Kanai–Tajimi noise.

Intensity convention (paper eq. 39): the driving white noise has
``E[xi(t) xi(s)] = 2 pi S0 delta(t - s)``, i.e. ``S0`` [m^2/s^3] is the constant level of
its two-sided power spectral density over ``-inf < omega < inf``.  The horizontal ground
acceleration is ``q(t) xi(t)`` (white) or ``q(t) z(t)`` with ``z`` the Kanai–Tajimi filter
output (eqs. 47–49).

Method and how it is checked: ``docs/method.md#excitation``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np

from screening.validation import checked

#: Integer codes of the envelope kinds, as the compiled solvers see them.
ENVELOPE_CODES = {"exponential": 0, "constant": 1}


@dataclass(frozen=True)
class Envelope:
    """Pulse-like modulation ``q(t) = 4 (exp(-t/T1) - exp(-t/T2))`` (eq. 57).

    ``T1`` > ``T2`` > 0 [s].  The default (``T1 = 4 s``, ``T2 = 2 s``) peaks at ``q = 1`` at
    ``t = 4 ln 2 s``.
    """

    T1: float = 4.0
    T2: float = 2.0

    kind = "exponential"

    def __post_init__(self):
        object.__setattr__(self, "T1", checked("T1", self.T1, lower=0.0))
        object.__setattr__(self, "T2", checked("T2", self.T2, lower=0.0))
        if np.any(np.asarray(self.T2) >= np.asarray(self.T1)):
            raise ValueError(
                f"parameter 'T2' must be smaller than 'T1' (0 < T2 < T1; got T1={self.T1!r}, T2={self.T2!r})")

    def __call__(self, t):
        """``q(t)`` [1] at times ``t`` [s] (an ``xarray.DataArray`` of times broadcasts by dimension name
        with DataArray ``T1``, ``T2``)."""
        if not hasattr(t, "dims"):
            t = np.asarray(t, dtype=float)
        return 4.0 * (np.exp(-t / self.T1) - np.exp(-t / self.T2))

    @property
    def params(self):
        """``(code, T1, T2)`` for the compiled solvers."""
        return ENVELOPE_CODES[self.kind], self.T1, self.T2


@dataclass(frozen=True)
class ConstantEnvelope:
    """Stationary excitation switched on at ``t = 0``: ``q(t) = 1``."""

    kind = "constant"

    def __call__(self, t):
        """``q(t) = 1`` [1] at times ``t`` [s]."""
        return np.ones_like(np.asarray(t, dtype=float))

    @property
    def params(self):
        """``(code, T1, T2)`` for the compiled solvers (T1, T2 unused)."""
        return ENVELOPE_CODES[self.kind], 1.0, 0.5


@dataclass(frozen=True)
class WhiteNoise:
    """Modulated Gaussian white noise ``q(t) xi(t)`` (eq. 39).

    ``S0`` [m^2/s^3]: two-sided PSD level of ``xi``, ``E[xi(t) xi(s)] = 2 pi S0 delta(t-s)``; > 0.
    """

    S0: float
    envelope: Envelope | ConstantEnvelope = field(default_factory=Envelope)

    kind = "white"

    def __post_init__(self):
        object.__setattr__(self, "S0", checked("S0", self.S0, lower=0.0))

    def psd(self, omega):
        """Two-sided PSD of the unmodulated input [m^2/s^3] at ``omega`` [rad/s]."""
        return self.S0 * np.ones_like(np.asarray(omega, dtype=float))


@dataclass(frozen=True)
class KanaiTajimi:
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

    def __post_init__(self):
        object.__setattr__(self, "S0", checked("S0", self.S0, lower=0.0))
        object.__setattr__(self, "omega_g", checked("omega_g", self.omega_g, lower=0.0))
        object.__setattr__(self, "zeta_g", checked("zeta_g", self.zeta_g, lower=0.0))

    def psd(self, omega):
        """Two-sided PSD of the filter output ``z`` [m^2/s^3] at ``omega`` [rad/s] (eq. 50)."""
        w = np.asarray(omega, dtype=float)
        wg, zg = self.omega_g, self.zeta_g
        num = wg**4 + 4.0 * zg**2 * wg**2 * w**2
        den = (w**2 - wg**2) ** 2 + 4.0 * zg**2 * wg**2 * w**2
        return self.S0 * num / den


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
