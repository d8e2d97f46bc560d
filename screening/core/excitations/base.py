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

from screening.core.registry import Registry
from screening.core.validation import checked

__all__ = ["Excitation", "Filter", "Parameter", "stationary_covariance", "transfer_psd"]

#: Default ground-motion band limit [Hz] of every excitation (its ``band_limit_hz``): the corner of the
#: low-pass :func:`band_gain` every model applies alike, and the band its intensity measures (and a
#: target PGA) refer to.  Strong-motion records are processed to about 25 Hz (low-pass corners of 20-30 Hz,
#: e.g. the PEER NGA processing); above it a rock-site acceleration spectrum has little energy (the
#: ``kappa`` decay).  A property of the ground motion, not of what stands on it.
GROUND_BAND_LIMIT_HZ = 25.0
#: Order ``n`` of the Butterworth low-pass of the band (docs/models.md, "The ground motion's band":
#: order 4 costs the moment solver 1.3-2x order 2 and removes 60x more of a white input above 2x the band).
BAND_ORDER = 4
#: ``|H|^2`` where the band's spectrum is cut for quadrature and synthesis (:func:`band_top`): above it a white
#: input keeps less than 1e-6 of its variance.
BAND_TAIL = 1e-6


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


def band_gain(omega, band_limit_hz, order=BAND_ORDER):
    """Squared gain ``|H|^2`` [1] of the band's Butterworth low-pass.

    Parameters
    ----------
    omega : array_like
        Circular frequency [rad s-1].
    band_limit_hz : array_like
        Corner frequency ``f_c`` [Hz], > 0 (broadcast with ``omega``).
    order : int, optional
        Butterworth order ``n`` (default :data:`BAND_ORDER`).

    Returns
    -------
    numpy.ndarray
        ``1 / (1 + (omega / (2 pi f_c))^(2 n))`` [1].

    Notes
    -----
    The maximally flat low-pass of order ``n`` [1]: ``|H|^2 = 1/2`` at the corner, ``-20 n`` dB per decade
    above it.  Every model multiplies the excitation's idealized PSD by it (:meth:`Excitation.psd`).

    References
    ----------
    .. [1] [butterworth1930] in the bibliography, ``docs/bibliography.md``.
    """
    w = np.asarray(omega, dtype=float) / (2.0 * math.pi * np.asarray(band_limit_hz, dtype=float))
    return 1.0 / (1.0 + w ** (2 * int(order)))


def band_top(band_limit_hz, order=BAND_ORDER, tail=BAND_TAIL):
    """Frequency [rad s-1] above which the band's ``|H|^2`` is below ``tail``: where its spectrum is cut.

    Parameters
    ----------
    band_limit_hz : float
        Corner frequency ``f_c`` [Hz], > 0.
    order : int, optional
        Butterworth order ``n`` (default :data:`BAND_ORDER`).
    tail : float, optional
        ``|H|^2`` at the cut [1] (default :data:`BAND_TAIL`).

    Returns
    -------
    float
        ``2 pi f_c (1 / tail - 1)^(1 / (2 n))`` [rad s-1] (5.6 x the corner for order 4).

    Notes
    -----
    The spectral representation of a band-limited input stops here and the intensity measures integrate
    its spectrum up to here (:meth:`Excitation.reference_cutoff`); a white input loses
    ``(omega_top / omega_c)^(1 - 2 n) / (2 n - 1)`` of ``2 S0 omega_c`` above it (1.2e-6 for order 4).

    References
    ----------
    .. [1] [butterworth1930] in the bibliography, ``docs/bibliography.md``.
    """
    return 2.0 * math.pi * float(band_limit_hz) * (1.0 / float(tail) - 1.0) ** (1.0 / (2 * int(order)))


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


def cascade(first, second):
    """The filter ``second`` driven by the output of ``first``, batched over the leading axes.

    Parameters
    ----------
    first, second : screening.core.excitations.Filter
        ``(A, B, C, D)`` of the two filters (leading axes broadcast together).

    Returns
    -------
    screening.core.excitations.Filter
        States ``(x1, x2)``: ``A = [[A1, 0], [B2 C1, A2]]``, ``B = [B1, B2 D1]``, ``C = [D2 C1, C2]``,
        ``D = D2 D1``.

    Notes
    -----
    Series connection of two state-space systems: ``x1' = A1 x1 + B1 w``, ``a = C1 x1 + D1 w`` and
    ``x2' = A2 x2 + B2 a``, output ``C2 x2 + D2 a`` (e.g. [1], ch. 2).

    References
    ----------
    .. [1] K. Zhou, J. C. Doyle and K. Glover, Robust and Optimal Control, Prentice Hall (1996).
    """
    A1, B1, C1, D1 = (np.asarray(m, dtype=float) for m in first)
    A2, B2, C2, D2 = (np.asarray(m, dtype=float) for m in second)
    lead = np.broadcast_shapes(A1.shape[:-2], A2.shape[:-2], np.shape(D1), np.shape(D2))
    n1, n2 = A1.shape[-1], A2.shape[-1]
    A = np.zeros(lead + (n1 + n2, n1 + n2))
    A[..., :n1, :n1] = A1
    A[..., n1:, n1:] = A2
    A[..., n1:, :n1] = B2[..., :, None] * C1[..., None, :]
    B = np.concatenate([np.broadcast_to(B1, lead + (n1,)), np.broadcast_to(B2 * D1[..., None], lead + (n2,))], -1)
    C = np.concatenate([np.broadcast_to(D2[..., None] * C1, lead + (n1,)), np.broadcast_to(C2, lead + (n2,))], -1)
    return Filter(A, B, C, np.broadcast_to(D2 * D1, lead).copy())


def band_filter(band_limit_hz, order=BAND_ORDER):
    """State-space matrices of the band's Butterworth low-pass, batched over ``band_limit_hz``.

    Parameters
    ----------
    band_limit_hz : array_like
        Corner frequency ``f_c`` [Hz], > 0.
    order : int, optional
        Butterworth order ``n``, even (default :data:`BAND_ORDER`).

    Returns
    -------
    screening.core.excitations.Filter
        ``n`` states ``(y_1, y_1', ..., y_{n/2}, y_{n/2}')`` [m s-2, m s-3]: ``A`` [..., n, n], ``B``, ``C``
        [..., n], ``D = 0``; its squared gain is :func:`band_gain`.

    Notes
    -----
    A cascade of ``n / 2`` second-order sections ``y'' + 2 zeta_k omega_c y' + omega_c^2 y = omega_c^2 u``
    with ``zeta_k = sin((2 k - 1) pi / (2 n))``, the pole pairs of the Butterworth polynomial [1]; each
    section's output is the next one's input, the last one's is the band-limited acceleration.

    References
    ----------
    .. [1] [butterworth1930] in the bibliography, ``docs/bibliography.md``.
    """
    n = int(order)
    if n < 2 or n % 2:
        raise ValueError(f"parameter 'order' must be an even integer >= 2 (got {order!r})")
    wc = 2.0 * math.pi * np.asarray(band_limit_hz, dtype=float)
    zero, one = np.zeros_like(wc), np.ones_like(wc)
    out = None
    for k in range(1, n // 2 + 1):
        z = math.sin((2 * k - 1) * math.pi / (2 * n))
        A = np.stack([np.stack([zero, one], -1), np.stack([-wc * wc, -2.0 * z * wc], -1)], -2)
        section = Filter(A, np.stack([zero, wc * wc], -1), np.stack([one, zero], -1), zero)
        out = section if out is None else cascade(out, section)
    return out


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
    """Base of the excitation classes (frozen dataclasses with fields ``S0``, the :attr:`parameters`,
    ``envelope`` and ``band_limit_hz``).  Subclasses set :attr:`kind`, :attr:`description`,
    :attr:`parameters` and implement :meth:`shaping_filter` (and :meth:`shaping_psd` where they have it in
    closed form); the base class appends the band's low-pass to both (:meth:`filter`, :meth:`psd`).

    ``band_limit_hz`` [Hz]: the corner of the Butterworth low-pass :func:`band_filter` every model applies
    alike (default :data:`GROUND_BAND_LIMIT_HZ`); ``None``: the idealized spectrum, unbounded in frequency
    (the paper's inputs)."""

    #: registry name (``kind = ...`` in studies, the ``excitation`` attribute of results)
    kind = ""
    #: one line for attributes and reports
    description = ""
    #: ``{name: Parameter}`` of the numeric parameters besides ``S0`` (study keys, sweepable)
    parameters = {}

    def __init_subclass__(cls, **kwargs):
        """A subclass declaring its own :attr:`kind` registers itself (:mod:`screening.core.excitations.registry`)."""
        super().__init_subclass__(**kwargs)
        if "kind" in vars(cls) and cls.kind:
            KINDS.add(cls.kind, cls)

    def __post_init__(self):
        """Validate ``S0`` (> 0), the :attr:`parameters` (their declared ranges) and ``band_limit_hz``
        (None or a finite number > 0 Hz); one line naming the parameter and its range otherwise."""
        object.__setattr__(self, "S0", checked("S0", self.S0, lower=0.0))
        for name, p in self.parameters.items():
            object.__setattr__(self, name, checked(name, getattr(self, name), lower=p.lower,
                                                   lower_inclusive=p.lower_inclusive, upper=p.upper,
                                                   upper_inclusive=True))
        band = getattr(self, "band_limit_hz", None)
        if band is not None:
            if isinstance(band, str):
                raise ValueError(f"parameter 'band_limit_hz' must be None (no band) or a finite number > 0 Hz "
                                 f"(got {band!r})")
            object.__setattr__(self, "band_limit_hz", checked("band_limit_hz", band, lower=0.0))

    def shaping_filter(self):
        """:class:`Filter` of the idealized spectrum (array fields: one set per element, leading axes)."""
        raise NotImplementedError

    def filter(self):
        """:class:`Filter` of this excitation: :meth:`shaping_filter` followed by the band's low-pass
        (:func:`band_filter`, :data:`BAND_ORDER` more states) unless ``band_limit_hz`` is None."""
        shaping = self.shaping_filter()
        band = getattr(self, "band_limit_hz", None)
        return shaping if band is None else cascade(shaping, band_filter(band, BAND_ORDER))

    def shaping_psd(self, omega):
        """Two-sided PSD of the idealized spectrum [m^2/s^3] at ``omega`` [rad/s] (scalar fields)."""
        return transfer_psd(self.shaping_filter(), float(self.S0), omega)

    def psd(self, omega):
        """Two-sided PSD of the unmodulated input [m^2/s^3] at ``omega`` [rad/s]: :meth:`shaping_psd` times the
        band's :func:`band_gain` (the transfer function of :meth:`filter`)."""
        band = getattr(self, "band_limit_hz", None)
        value = self.shaping_psd(omega)
        return value if band is None else value * band_gain(omega, band, BAND_ORDER)

    def psd_peaks(self):
        """Frequencies [rad/s] where :meth:`psd` may peak or bend (break points for quadrature)."""
        peaks = [float(getattr(self, name)) for name, p in self.parameters.items() if p.units == "rad s-1"]
        band = getattr(self, "band_limit_hz", None)
        return peaks + ([] if band is None else [2.0 * math.pi * band])

    def reference_cutoff(self):
        """The band [rad/s] the intensity measures integrate :meth:`psd` over and the Monte Carlo synthesis
        reaches: :func:`band_top` of ``band_limit_hz`` (5.6 x its corner), or, for the idealized spectrum,
        a sharp cut at :data:`GROUND_BAND_LIMIT_HZ` (the intensity measures; the synthesis then keeps its
        own cut-off)."""
        band = getattr(self, "band_limit_hz", None)
        return ground_cutoff() if band is None else band_top(band, BAND_ORDER)

    def stationary_covariance(self):
        """Stationary covariance of the filter states (:func:`stationary_covariance`); NaN at a point whose
        idealized filter has no stationary state (the stable band's low-pass after it can hide that singularity
        from the solve in rounding)."""
        cov = stationary_covariance(self.filter(), self.S0)
        shaping = self.shaping_filter()
        if getattr(self, "band_limit_hz", None) is None or not np.shape(shaping.A)[-1]:
            return cov
        alone = stationary_covariance(shaping, self.S0)
        bad = ~np.all(np.isfinite(alone.reshape(alone.shape[:-2] + (-1,))), axis=-1)
        return np.where(bad[..., None, None], np.nan, cov)

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


#: The registered excitation classes by kind (filled by subclassing :class:`Excitation`).
KINDS = Registry("kind")
