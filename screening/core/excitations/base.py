"""The interface every excitation implements (see ``docs/architecture_models.md``).

An excitation is the modulated ground acceleration ``q(t) a(t)`` where ``a`` is the output of a
linear time-invariant filter driven by Gaussian white noise ``w`` of two-sided PSD ``S0``
(``E[w(t) w(s)] = 2 pi S0 delta(t - s)``)::

    x' = A x + B w,        a = C x + D w

with ``n_f`` filter states ``x`` (``n_f = 0`` and ``D = 1``: white noise).  The filter, as the
matrices ``(A, B, C, D)``, is all the moment equations need (the augmented Lyapunov system of
:mod:`screening.solvers.moment_equations`); its PSD ``S(omega) = S0 |C (i omega - A)^-1 B + D|^2``
is what the Monte Carlo synthesis and the intensity measures need.  An excitation class declares
its parameters (study keys with their allowed ranges and CF attributes); it is registered by its
``kind``.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy import integrate

from screening.core.validation import checked

__all__ = ["GROUND_BAND_LIMIT_HZ", "ground_cutoff", "Parameter", "Filter", "transfer_psd", "stationary_covariance",
           "Excitation"]

#: Default ground-motion band limit [Hz] of a stochastic input: the band its intensity measures (and a
#: target PGA) refer to.  Strong-motion records are processed to about 25 Hz (low-pass corners of 20-30 Hz,
#: e.g. the PEER NGA processing); above it a rock-site acceleration spectrum has little energy (the
#: ``kappa`` decay).  A property of the ground motion, not of what stands on it: the Monte Carlo
#: synthesis may extend its own band for numerics (3 x the bed's frequencies), the label stays this one.
GROUND_BAND_LIMIT_HZ = 25.0


def ground_cutoff(band_limit_hz=GROUND_BAND_LIMIT_HZ):
    """The band limit ``omega_c = 2 pi f`` [rad s-1] of a ground motion band-limited to ``f``.

    Parameters
    ----------
    band_limit_hz : float, optional
        Band limit ``f`` [Hz] (default :data:`GROUND_BAND_LIMIT_HZ`, 25 Hz).

    Returns
    -------
    float
        ``omega_c`` [rad s-1].

    Notes
    -----
    The frequency up to which the intensity measures integrate the input's spectrum; strong-motion
    records are processed to about this band (module constant's comment).  The modulated inputs of
    [1] (eqs. (39) and (47)) are not band-limited; their intensity measures are.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> f"{ground_cutoff():.4f}"
    '157.0796'
    """
    return 2.0 * math.pi * float(band_limit_hz)


class Parameter(NamedTuple):
    """A numeric parameter of an excitation (besides ``S0``): its CF attributes and allowed range
    (``lower`` bound, inclusive or not; ``upper`` bound or None)."""

    units: str
    long_name: str
    lower: float = 0.0
    lower_inclusive: bool = False
    upper: float | None = None


class Filter(NamedTuple):
    """State-space matrices of an excitation's shaping filter, one set per point (leading axes).

    ``A`` [..., n_f, n_f] [1/s], ``B`` [..., n_f], ``C`` [..., n_f], ``D`` [...]: ``x' = A x + B w``,
    ``a = C x + D w`` (units follow the states; ``a`` in m/s^2 for ``w`` in m/s^2).
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray


def transfer_psd(filt, S0, omega):
    """Two-sided PSD of a shaping filter's output [m2 s-3] (scalar filter: no leading axes).

    Parameters
    ----------
    filt : screening.core.excitations.Filter
        The filter's ``(A, B, C, D)``.
    S0 : float
        Two-sided PSD level of the driving white noise [m2 s-3].
    omega : array_like
        Circular frequency [rad s-1], any shape.

    Returns
    -------
    numpy.ndarray
        ``S0 |C (i omega - A)^-1 B + D|^2`` [m2 s-3], shaped like ``omega``.

    Notes
    -----
    The squared gain of the filter's transfer function times the input's level: eq. (50) in [1] for the
    Kanai–Tajimi filter.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> from screening.core.excitations.kanai_tajimi import kanai_tajimi_filter, kanai_tajimi_psd
    >>> f = kanai_tajimi_filter(10.0, 0.4)
    >>> bool(abs(transfer_psd(f, 1e-3, 7.0) - kanai_tajimi_psd(7.0, 1e-3, 10.0, 0.4)) < 1e-15)
    True
    """
    omega = np.asarray(omega, dtype=float)
    A, B, C, D = (np.asarray(m, dtype=float) for m in filt)
    n = A.shape[-1]
    flat = omega.reshape(-1)
    if n == 0:
        h = np.full(flat.shape, complex(D))
    else:
        eye = np.eye(n)
        h = np.array([C @ np.linalg.solve(1j * w * eye - A, B) for w in flat]) + D
    return (S0 * np.abs(h) ** 2).reshape(omega.shape)


def stationary_covariance(filt, S0):
    """Stationary covariance of a filter's states, batched over the leading axes.

    Parameters
    ----------
    filt : screening.core.excitations.Filter
        The filter's ``(A, B, C, D)``, ``A`` [..., n_f, n_f], ``B`` [..., n_f].
    S0 : array_like
        Two-sided PSD level of the driving white noise [m2 s-3], broadcast with the leading axes.

    Returns
    -------
    numpy.ndarray
        ``P`` [..., n_f, n_f] in the squared units of the states.

    Notes
    -----
    The solution of ``A P + P A^T + 2 pi S0 B B^T = 0``, the stationary form of the Lyapunov equation
    (eq. (51) in [1]) for the filter block; in Kronecker form ``vec(A P + P A^T) = (I (x) A + A (x) I)
    vec(P)``, solved per point with :func:`numpy.linalg.solve`; NaN at a point whose filter has no stationary
    state (a singular system: a pole at zero, e.g. a high-pass frequency or damping ratio underflowing).

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.

    Examples
    --------
    >>> from screening.core.excitations.kanai_tajimi import kanai_tajimi_filter
    >>> P = stationary_covariance(kanai_tajimi_filter(10.0, 0.4), 1e-3)
    >>> [f"{v:.4g}" for v in (P[0, 0], P[1, 1])]
    ['3.927e-06', '0.0003927']
    """
    A = np.asarray(filt.A, dtype=float)
    B = np.asarray(filt.B, dtype=float)
    n = A.shape[-1]
    lead = A.shape[:-2]
    eye = np.eye(n)
    kron = np.einsum("ij,...kl->...ikjl", eye, A).reshape(lead + (n * n, n * n)) \
        + np.einsum("...ij,kl->...ikjl", A, eye).reshape(lead + (n * n, n * n))
    q = 2.0 * math.pi * np.asarray(S0, dtype=float)[..., None, None] * B[..., :, None] * B[..., None, :]
    rhs = -np.swapaxes(q, -1, -2).reshape(lead + (n * n, 1))
    try:
        p = np.linalg.solve(kron, rhs)[..., 0]
    except np.linalg.LinAlgError:           # a degenerate filter (a pole at 0): NaN at that point alone
        flat_k = np.broadcast_to(kron, lead + (n * n, n * n)).reshape(-1, n * n, n * n)
        flat_r = np.broadcast_to(rhs, lead + (n * n, 1)).reshape(-1, n * n, 1)
        p = np.full((flat_k.shape[0], n * n), np.nan)
        for i in range(flat_k.shape[0]):
            try:
                p[i] = np.linalg.solve(flat_k[i], flat_r[i])[:, 0]
            except np.linalg.LinAlgError:
                pass
    return np.swapaxes(p.reshape(lead + (n, n)), -1, -2)


class Excitation:
    """Base of the excitation classes (frozen dataclasses with fields ``S0``, the :attr:`parameters`
    and ``envelope``).  Subclasses set :attr:`kind`, :attr:`description`, :attr:`parameters` and
    implement :meth:`filter`; :meth:`psd` defaults to the filter's transfer function."""

    #: registry name (``kind = ...`` in studies, the ``excitation`` attribute of results)
    kind = ""
    #: one line for attributes and reports
    description = ""
    #: ``{name: Parameter}`` of the numeric parameters besides ``S0`` (study keys, sweepable)
    parameters = {}

    def __post_init__(self):
        """Validate ``S0`` (> 0) and the :attr:`parameters` (their declared ranges); one line naming the
        parameter and its range otherwise."""
        object.__setattr__(self, "S0", checked("S0", self.S0, lower=0.0))
        for name, p in self.parameters.items():
            object.__setattr__(self, name, checked(name, getattr(self, name), lower=p.lower,
                                                   lower_inclusive=p.lower_inclusive, upper=p.upper,
                                                   upper_inclusive=True))

    def filter(self):
        """:class:`Filter` of this excitation (array fields: one set per element, leading axes)."""
        raise NotImplementedError

    def psd(self, omega):
        """Two-sided PSD of the unmodulated input [m^2/s^3] at ``omega`` [rad/s] (scalar fields)."""
        return transfer_psd(self.filter(), float(self.S0), omega)

    def psd_peaks(self):
        """Frequencies [rad/s] where :meth:`psd` may peak (break points for quadrature)."""
        return [float(getattr(self, name)) for name, p in self.parameters.items() if p.units == "rad s-1"]

    def stationary_covariance(self):
        """Stationary covariance of the filter states (:func:`stationary_covariance`)."""
        return stationary_covariance(self.filter(), self.S0)

    def spectral_moment(self, order, cutoff, epsrel=1e-11):
        """``lambda_i = int_{-omega_c}^{omega_c} |omega|^i S(omega) d omega`` of the unmodulated input
        band-limited to ``cutoff`` [rad/s] (``i = order``; [m2 s-4], [m2 s-5], [m2 s-6] for i = 0, 1, 2),
        by adaptive quadrature with :meth:`psd_peaks` as break points (scalar fields).  Raises
        ``ArithmeticError`` where the quadrature does not converge (a degenerate filter: the point is
        flagged by the caller, never given a wrong moment)."""
        cutoff = float(cutoff)
        # break points QUADPACK can split at: inside the band and not within rounding of its ends (a filter
        # frequency of 1e-300 as a break point crashes QUADPACK itself, the whole process)
        points = [p for p in self.psd_peaks() if math.isfinite(p) and 1e-9 * cutoff < p < (1.0 - 1e-9) * cutoff]
        if not math.isfinite(float(self.psd(0.5 * cutoff))):
            raise ArithmeticError(f"spectral moment lambda_{order}: the spectrum is not finite (a filter parameter "
                                  "beyond float range)")
        value, _, *problem = integrate.quad(lambda w: w**order * float(self.psd(w)), 0.0, cutoff, limit=400,
                                            points=points or None, epsrel=epsrel, full_output=1)
        if len(problem) > 1:                       # quad's message: the integral did not converge
            raise ArithmeticError(f"spectral moment lambda_{order}: {' '.join(str(problem[1]).split())}")
        return 2.0 * value
