"""Stochastic ground excitation: the envelopes (the excitations are in :mod:`screening.core.excitations`).

Intensity convention (paper eq. 39): the driving white noise has
``E[xi(t) xi(s)] = 2 pi S0 delta(t - s)``, i.e. ``S0`` [m^2/s^3] is the constant level of
its two-sided power spectral density over ``-inf < omega < inf``.  The horizontal ground
acceleration is ``q(t) xi(t)`` (white) or ``q(t) z(t)`` with ``z`` the Kanai–Tajimi filter
output (eqs. 47–49).

Method and how it is checked: ``docs/method.md#excitation``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from screening.core.validation import checked

__all__ = ["Envelope", "ConstantEnvelope"]

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
