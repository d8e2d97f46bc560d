"""Modulated Gaussian white noise (paper eq. 39): no filter, ``a = w``."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from screening.core.excitations.base import GROUND_BAND_LIMIT_HZ, Excitation, Filter
from screening.core.model.excitation import ConstantEnvelope, Envelope

__all__ = ["WhiteNoise"]


@dataclass(frozen=True)
class WhiteNoise(Excitation):
    """Modulated Gaussian white noise ``q(t) xi(t)`` (eq. 39).

    ``S0`` [m^2/s^3]: two-sided PSD level of ``xi``, ``E[xi(t) xi(s)] = 2 pi S0 delta(t-s)``; > 0.
    ``band_limit_hz`` [Hz]: corner of the band's low-pass (:class:`~screening.core.excitations.Excitation`); None:
    unbounded white noise (the paper's).
    """

    S0: float
    envelope: Envelope | ConstantEnvelope = field(default_factory=Envelope)
    band_limit_hz: float | None = GROUND_BAND_LIMIT_HZ

    kind = "white"
    description = "modulated white noise (eq. 39)"
    parameters = {}


    def shaping_filter(self):
        """No state: ``A``, ``B``, ``C`` empty, ``D = 1``."""
        shape = np.shape(self.S0)
        return Filter(np.zeros(shape + (0, 0)), np.zeros(shape + (0,)), np.zeros(shape + (0,)), np.ones(shape))

    def shaping_psd(self, omega):
        """Two-sided PSD of the idealized input [m^2/s^3] at ``omega`` [rad/s]: ``S0``."""
        return self.S0 * np.ones_like(np.asarray(omega, dtype=float))

    def spectral_moment(self, order, cutoff, epsrel=None):
        """Closed form of :meth:`Excitation.spectral_moment`: ``2 S0 omega_c^(i+1) / (i + 1)``
        (``2 S0 omega_c``, ``S0 omega_c^2``, ``2 S0 omega_c^3 / 3``) without a band; the quadrature with one."""
        if self.band_limit_hz is not None:
            return super().spectral_moment(order, cutoff, **({} if epsrel is None else {"epsrel": epsrel}))
        s0, wc = float(self.S0), float(cutoff)
        return (2.0 * s0 * wc, s0 * wc**2, 2.0 * s0 * wc**3 / 3.0)[order] if order < 3 else \
            2.0 * s0 * wc ** (order + 1) / (order + 1)
