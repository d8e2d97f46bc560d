"""Random-vibration (RVT) peak factors of the stochastic inputs: the first-passage medians of PGA and Sa.

At every time ``(y, y')`` is Gaussian for ``y`` the ground acceleration, an oscillator's response or the
high-passed velocity: their non-stationary moments (:func:`input_moments`, :func:`oscillator_covariance`,
:func:`velocity_covariance`) and the peak distribution ``P(max_t |y| <= x) = exp(-int_0^T nu(x, t) dt)``
with Rice's rate ``nu`` [rice1944] give :func:`pga_median` (crossings independent) and :func:`sa_median`
(Vanmarcke's clumping [vanmarcke1975]).  Method, accuracy and limits: ``docs/intensity_measures.md``.
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np
from scipy import integrate, linalg, optimize

from screening.analysis._excitation_shape import (N_TIMES, distinct_points as _distinct_points,
                                                  scalar_excitation as _scalar_excitation,
                                                  shape_key as _shape_key, shape_names as _shape_names, times as _times)
from screening.analysis.fragility import (exceedance_probability_from_moments, oscillator_bandwidth, upcrossing_rate,
                                          vanmarcke_factor)
from screening.analysis.intensity_records import OMEGA_LOW
from screening.solvers.synthesis import envelope_rate

__all__ = ["spectral_moments", "median_peak", "input_moments", "pga_median", "rocking_start_probability",
           "oscillator_covariance", "sa_median", "oscillator_response_bandwidth", "velocity_spectral_moments",
           "envelope_exponentials", "velocity_covariance"]

#: Points evaluated together by :func:`rocking_start_probability`.
CHUNK_POINTS = 64


def spectral_moments(excitation, cutoff):
    """The first three spectral moments of the unmodulated input band-limited to ``cutoff``.

    ``ArithmeticError`` where the quadrature of a Kanai-Tajimi moment does not converge (a filter so
    narrow, ``zeta_g`` ~ 1e-9, that its peak escapes the quadrature).

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        A registered excitation (scalar fields) with its two-sided PSD ``S(omega)`` [m2 s-3].
    cutoff : float
        Band limit ``omega_c`` [rad s-1].

    Returns
    -------
    tuple of float
        ``(lambda_0, lambda_1, lambda_2)`` [m2 s-4], [m2 s-5], [m2 s-6].

    Notes
    -----
    ``lambda_i = int_{-omega_c}^{omega_c} |omega|^i S(omega) d omega`` [1]; band-limited white noise
    has ``lambda_i = 2 S0 omega_c^(i+1) / (i + 1)``.

    References
    ----------
    [1] [vanmarcke1975].

    Examples
    --------
    >>> from screening.core.model.excitation import ConstantEnvelope
    >>> from screening.core.excitations.white import WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> spectral_moments(white, 50.0)
    (1.0, 25.0, 833.33...)
    >>> 2 * 0.01 * 50.0 ** 3 / 3
    833.33...
    """
    return tuple(excitation.spectral_moment(i, float(cutoff), epsrel=1e-11) for i in range(3))


def median_peak(t, var, var_dot, cov, bandwidth=None, probability=0.5):
    """The level a non-stationary Gaussian process stays below with a given probability (its median peak).

    Level ``x`` with ``P(max_t |y| <= x) = probability`` for a zero-mean Gaussian ``y`` with the given
    moments on times ``t``; 0 for a process of zero variance.

    Parameters
    ----------
    t : numpy.ndarray
        Times [s].
    var, var_dot, cov : numpy.ndarray
        ``var y``, ``var y'`` and ``cov(y, y')`` on ``t`` [units of y squared, per s^2, per s].
    bandwidth : float, optional
        Vanmarcke's bandwidth ``delta`` [1] for clumped crossings; ``None`` (default): crossings
        independent.
    probability : float, default 0.5
        Probability of not exceeding [1].

    Returns
    -------
    float
        The level ``x`` [units of y].

    Notes
    -----
    ``P(max_t |y| <= x) = exp(-int_0^T nu(x, t) dt)`` with Rice's rate of crossings of ``|y| = x``
    [1] of the non-stationary pair ``(y, y')`` (:func:`screening.analysis.fragility.upcrossing_rate`),
    times Vanmarcke's clumping factor [2] when ``bandwidth`` is given; solved for ``x`` by Brent's
    method.

    References
    ----------
    [1] [rice1944]; [2] [vanmarcke1975].

    Examples
    --------
    A stationary unit-variance process of frequency 2 rad/s over 10 s: Rice's rate of crossings of
    ``|y| = x`` is ``(2 / pi) exp(-x^2 / 2)``.

    >>> import math, numpy as np
    >>> t = np.linspace(0.0, 10.0, 2001)
    >>> x = median_peak(t, np.ones_like(t), np.full_like(t, 4.0), np.zeros_like(t))
    >>> f"{x:.6f}", f"{math.sqrt(2 * math.log(20 / math.pi / math.log(2))):.6f}"
    ('2.105951', '2.105951')
    """
    target = -math.log(probability)
    sigma = math.sqrt(float(np.max(var)))
    if not sigma > 0.0:
        return 0.0

    def excess(log_x):
        x = math.exp(log_x)
        rate = upcrossing_rate(var, var_dot, cov, x)
        if bandwidth is not None:
            rate = rate * vanmarcke_factor(var, x, bandwidth)
        return float(np.trapezoid(rate, t)) - target

    lo, hi = math.log(0.05 * sigma), math.log(20.0 * sigma)
    while excess(lo) < 0.0:
        lo -= 1.0
    return math.exp(optimize.brentq(excess, lo, hi, xtol=1e-10))


def input_moments(excitation, t_end, cutoff):
    """The non-stationary moments of the modulated, band-limited ground acceleration.

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        A registered excitation (scalar fields) with its envelope.
    t_end : float
        Record length [s].
    cutoff : float
        Band limit [rad s-1].

    Returns
    -------
    tuple
        ``(t, var a, var a', cov(a, a'), delta)`` on :data:`N_TIMES` times over ``[0, t_end]``:
        [s], [m2 s-4], [m2 s-6], [m2 s-5] and Vanmarcke's bandwidth [1].

    Notes
    -----
    For ``a = q(t) f(t)``: ``var a = q^2 lambda_0``, ``var a' = q^2 lambda_2 + q'^2 lambda_0``,
    ``cov(a, a') = q q' lambda_0`` and ``delta = sqrt(1 - lambda_1^2 / (lambda_0 lambda_2))`` [1] with
    the moments of :func:`spectral_moments`; the envelope is eq. (57) in [2].

    References
    ----------
    [1] [vanmarcke1975]; [2] [mitseas2026].

    Examples
    --------
    >>> from screening.core.model.excitation import ConstantEnvelope
    >>> from screening.core.excitations.white import WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> t, var, var_dot, cov, delta = input_moments(white, 10.0, 50.0)
    >>> t.shape, float(var[0]), float(var_dot[0]), float(cov[0]), round(delta, 6)
    ((4001,), 1.0, 833.33..., 0.0, 0.5)
    """
    lam0, lam1, lam2 = spectral_moments(excitation, cutoff)
    t = _times(t_end)
    q = excitation.envelope(t)
    qd = envelope_rate(excitation.envelope, t)
    delta = math.sqrt(max(1.0 - lam1**2 / (lam0 * lam2), 0.0))
    return t, q * q * lam0, q * q * lam2 + qd * qd * lam0, q * qd * lam0, delta


def pga_median(excitation, t_end, cutoff):
    """RVT median peak ground acceleration of the modulated input.

    The median of the distribution of :func:`rocking_start_probability` (Rice's rate, crossings not
    clumped).  The study's ``pga_median`` is the simulated one
    (:func:`screening.analysis.intensity.pga_median`): this one is +3.0 % high for soft soil, where
    crossings clump.

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        A registered excitation (scalar fields) with its envelope.
    t_end : float
        Record length [s].
    cutoff : float
        Band limit [rad s-1].

    Returns
    -------
    float
        Median of ``max_t |a(t)|`` [m s-2].

    Notes
    -----
    :func:`median_peak` of :func:`input_moments`: ``exp(-int_0^T nu(x, t) dt) = 1/2`` with Rice's rate
    ``nu`` [1], [2].

    References
    ----------
    [1] [rice1944]; [2] [vanmarcke1975].

    Examples
    --------
    >>> from screening.core.model.excitation import ConstantEnvelope
    >>> from screening.core.excitations.white import WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> pga = pga_median(white, 10.0, 50.0)
    >>> f"{pga:.4f}", f"{pga_median(WhiteNoise(0.04, white.envelope, band_limit_hz=None), 10.0, 50.0) / pga:.6f}"
    ('3.1264', '2.000000')
    """
    t, var, var_dot, cov, _ = input_moments(excitation, t_end, cutoff)
    return median_peak(t, var, var_dot, cov)


def rocking_start_probability(excitation, t_end, cutoff, uplift_acceleration, method="poisson"):
    """Probability [1] that ``|a_g|`` exceeds ``uplift_acceleration`` [m s-2] at least once over ``[0, t_end]``.

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        A registered excitation (:mod:`screening.core.excitations`; array fields broadcast with the others).
    t_end : float
        Record length [s].
    cutoff : float or array_like
        Band limit of the ground motion [rad s-1] (:func:`ground_cutoff`, the one its PGA refers to).
    uplift_acceleration : float or array_like
        Ground acceleration at which the block starts to rock [m s-2]
        (:func:`screening.analysis.probabilities.uplift_acceleration`).
    method : {"poisson", "vanmarcke"}, default "poisson"
        ``"poisson"``: independent crossings, the distribution whose median is :func:`pga_median`;
        ``"vanmarcke"``: clumped crossings.

    Returns
    -------
    float or numpy.ndarray
        The probability [1] over the broadcast points.

    Notes
    -----
    The distribution of the peak ground acceleration of which :func:`pga_median` is the median:
    ``P(max_t |a| > x) = 1 - exp(-int_0^T nu(x, t) dt)`` with Rice's double-barrier rate ``nu`` of the
    non-stationary pair ``(a, a')`` (:func:`screening.analysis.fragility.exceedance_probability_from_moments`).
    The ground acceleration is broad-band, so Poisson (independent crossings) is the default; the
    moments scale with ``S0``, so one evaluation at ``S0 = 1`` serves every point.  RVT rather than
    simulation because the probability can be small; its bias (conservative on soft soil) and its
    check against synthesised records: ``docs/intensity_measures.md``.

    References
    ----------
    [1] [rice1944]; [2] [vanmarcke1975].

    Examples
    --------
    At the RVT median PGA the probability is one half:

    >>> from screening.core.model.excitation import ConstantEnvelope
    >>> from screening.core.excitations.white import WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> p = rocking_start_probability(white, 5.0, 50.0, pga_median(white, 5.0, 50.0))
    >>> f"{p:.4f}"
    '0.5000'
    """
    if method not in ("poisson", "vanmarcke"):
        raise ValueError(f"parameter 'method' must be 'poisson' or 'vanmarcke' (got {method!r})")
    s0 = np.asarray(excitation.S0, dtype=float)
    level, s0, cut = np.broadcast_arrays(np.asarray(uplift_acceleration, dtype=float), s0,
                                         np.asarray(cutoff, dtype=float))
    names = _shape_names(excitation)
    filt = [np.broadcast_to(np.asarray(getattr(excitation, n), dtype=float), level.shape) for n in names]
    out = np.full(level.shape, np.nan)
    flat_out, flat_level, flat_s0 = out.reshape(-1), level.reshape(-1), s0.reshape(-1)
    for (*values, wc), rows in _distinct_points([*filt, cut], level.shape):
        try:
            x_grid, log_crossings = _unit_crossings(*_shape_key(excitation, t_end), names, tuple(values), wc, method)
        except (ArithmeticError, ValueError):          # scales beyond float64: NaN
            continue
        with np.errstate(divide="ignore", invalid="ignore"):
            x = flat_level[rows] / np.sqrt(flat_s0[rows])
            crossings = np.exp(np.interp(x, x_grid, log_crossings, right=-np.inf))
            flat_out[rows] = np.where(np.isfinite(x), -np.expm1(-crossings), np.nan)
    return float(out) if out.ndim == 0 else out


#: Levels per unit peak standard deviation of the table of :func:`_unit_crossings`, and its extent.
CROSSING_STEP, CROSSING_EXTENT = 0.02, 12.0


@functools.lru_cache(maxsize=256)
def _unit_crossings(*args):
    """``(x, log int_0^T nu(x, t) dt)`` at ``S0 = 1`` of one filter, envelope, ``t_end``, band limit and method,
    tabulated at levels ``x`` every :data:`CROSSING_STEP` peak standard deviations (``log`` of the expected
    crossings is nearly quadratic in ``x``: linear interpolation errs by about ``step^2 / 8``, 5e-5 relative;
    beyond the table, 12 peak standard deviations, the probability is below 1e-28 and read as 0)."""
    *shape, method = args
    t, var, var_dot, cov, delta = _unit_input_moments(*shape)
    x = np.arange(0.0, CROSSING_EXTENT, CROSSING_STEP) * math.sqrt(float(np.max(var)))
    crossings = np.empty_like(x)
    for lo in range(0, x.size, CHUNK_POINTS):              # bounded memory: levels x N_TIMES at a time
        p = exceedance_probability_from_moments(t, var, var_dot, cov, x[lo:lo + CHUNK_POINTS, None], method=method,
                                                bandwidth=delta)
        crossings[lo:lo + CHUNK_POINTS] = -np.log1p(-np.minimum(p, 1.0 - 1e-16))    # certain beyond ~37
    with np.errstate(divide="ignore"):
        log_crossings = np.log(crossings)
    keep = np.isfinite(log_crossings)                     # the levels no record reaches are read as 0
    return x[keep], log_crossings[keep]


@functools.lru_cache(maxsize=256)
def _unit_input_moments(kind, envelope_kind, *args):
    """:func:`input_moments` at ``S0 = 1`` of one filter (parameters ``names`` with ``values``),
    envelope, ``t_end`` and band limit."""
    *envelope, t_end, names, values, cutoff = args
    p = {**dict(zip(names, values)), **dict(zip(("T1", "T2"), envelope))}
    return input_moments(_scalar_excitation(kind, envelope_kind, p), t_end, cutoff)


def oscillator_covariance(excitation, period, t_end, damping=0.05, n_times=N_TIMES):
    """The non-stationary response moments of a linear oscillator driven by the ground acceleration.

    The oscillator ``u'' + 2 zeta omega_n u' + omega_n^2 u = -a(t)`` starts at rest, the excitation's
    filter states (:meth:`screening.core.excitations.base.Excitation.filter`) in their stationary state.

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        A registered excitation (scalar fields) with its envelope (exponential or constant).
    period : float
        Natural period ``T_n = 2 pi / omega_n`` [s].
    t_end : float
        Record length [s].
    damping : float, default 0.05
        Damping ratio ``zeta`` [1].
    n_times : int, default N_TIMES
        Output times over ``[0, t_end]``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(t [s], var_u [m2], var_u_dot [m2 s-2], cov(u, u') [m2 s-1])``.

    Notes
    -----
    The Lyapunov equation ``P' = A P + P A^T + 2 pi S0 q(t)^2 b b^T`` of the joint state (filter ``x``,
    ``u``, ``u'``) [1], as in eqs. (51)-(55) of [2] for the block; under stationary white noise the variance
    tends to ``pi S0 / (2 zeta omega_n^3)`` [3].  Solved exactly: the filter block stays stationary, so the
    cross-covariance ``X = P_xu`` and the oscillator's block ``Y`` are linear in each other with constant
    coefficients and a forcing in ``q`` and ``q^2``; with ``q`` a sum of exponentials
    (:func:`envelope_exponentials`) the states ``exp(-r_j t) X``, ``Y`` and ``exp(-(r_j + r_k) t)`` make a
    constant linear system, propagated from one output time to the next by one matrix exponential [4]
    (1e-13 of the variance from a tight adaptive integration).

    References
    ----------
    [1] [lutes2004]; [2] [mitseas2026]; [3] [clough1975]; [4] [vanloan1978].

    Examples
    --------
    >>> from screening.core.model.excitation import ConstantEnvelope
    >>> from screening.core.excitations.white import WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> import math
    >>> t, var_u, var_ud, cov = oscillator_covariance(white, 0.5, 3.0, damping=0.2, n_times=11)
    >>> wn = 2 * math.pi / 0.5
    >>> f"{var_u[-1]:.5e}", f"{math.pi * 0.01 / (2 * 0.2 * wn ** 3):.5e}"
    ('3.95786e-05', '3.95786e-05')
    """
    wn = 2.0 * math.pi / float(period)
    S0 = float(excitation.S0)
    A_f, B_f, C_f, D_f = (np.asarray(m, dtype=float) for m in excitation.filter())
    nf, nx = A_f.shape[0], 2 * A_f.shape[0]             # X = P_xo, row-major: 2 nf entries
    amps, rates = envelope_exponentials(excitation.envelope)
    m = amps.size
    A_o = np.array([[0.0, 1.0], [-wn * wn, -2.0 * float(damping) * wn]])
    E = np.zeros((2, nf))
    E[1] = -C_f
    d = np.array([0.0, -float(D_f)])
    S = excitation.stationary_covariance() if nf else np.zeros((0, 0))
    F = (S @ E.T + 2.0 * math.pi * S0 * np.outer(B_f, d)).ravel()
    i2 = np.eye(2)
    sym = np.eye(4) + np.eye(4)[[0, 2, 1, 3]]              # vec(Z) -> vec(Z + Z^T)
    # state: exp(-r_j t) X for each j, vec(Y), exp(-(r_j + r_k) t) for each (j, k); X' = A_f X + X A_o^T + q F,
    # Y' = A_o Y + Y A_o^T + q (E X + X^T E^T) + 2 pi S0 q^2 d d^T
    iy, ip = m * nx, m * nx + 4
    M = np.zeros((ip + m * m, ip + m * m))
    M[iy:ip, iy:ip] = np.kron(A_o, i2) + np.kron(i2, A_o)
    for j in range(m):
        xj = slice(j * nx, (j + 1) * nx)
        M[xj, xj] = np.kron(A_f, i2) + np.kron(np.eye(nf), A_o) - rates[j] * np.eye(nx)
        M[iy:ip, xj] = amps[j] * sym @ np.kron(E, i2)
        for k in range(m):
            M[xj, ip + j * m + k] = amps[k] * F
            M[ip + j * m + k, ip + j * m + k] = -(rates[j] + rates[k])
            M[iy:ip, ip + j * m + k] = amps[j] * amps[k] * 2.0 * math.pi * S0 * np.outer(d, d).ravel()
    t = _times(t_end, n_times)
    step = linalg.expm(M * (t[-1] / (t.size - 1)))
    state = np.zeros(M.shape[0])
    state[ip:] = 1.0                                        # at rest, exponentials at 1
    Y = np.zeros((t.size, 4))
    for i in range(1, t.size):
        state = step @ state
        Y[i] = state[iy:ip]
    return t, Y[:, 0], Y[:, 3], Y[:, 1]


def sa_median(excitation, period, t_end, damping=0.05, cutoff=None):
    """Median pseudo-spectral acceleration ``omega_n^2 max|u|`` of the input at one period (RVT).

    A ``UserWarning`` when ``omega_n`` is above half the band limit (the Lyapunov variance ignores it).

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        A registered excitation (scalar fields) with its envelope.
    period : float
        Natural period [s].
    t_end : float
        Record length [s].
    damping : float, default 0.05
        Damping ratio [1].
    cutoff : float, optional
        Band limit of the input [rad s-1] (``None``: unbounded); it sets the bandwidth of the response
        (:func:`oscillator_response_bandwidth`), not its variance.

    Returns
    -------
    float
        The median Sa [m s-2].

    Notes
    -----
    ``Sa = omega_n^2 x`` with ``x`` the :func:`median_peak` of :func:`oscillator_covariance` under
    Vanmarcke's clumping [1] for the larger of the white-noise bandwidth of the oscillator and that of
    its response to the input [2].

    References
    ----------
    [1] [vanmarcke1975]; [2] [derkiureghian1980].

    Examples
    --------
    Proportional to ``sqrt(S0)``:

    >>> from screening.core.model.excitation import ConstantEnvelope
    >>> from screening.core.excitations.white import WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> sa = sa_median(white, 0.5, 3.0, damping=0.2)
    >>> f"{sa:.4f}", f"{sa_median(WhiteNoise(0.04, white.envelope, band_limit_hz=None), 0.5, 3.0, damping=0.2) / sa:.6f}"
    ('2.1851', '2.000000')
    """
    wn = 2.0 * math.pi / float(period)
    if cutoff is not None and wn > 0.5 * float(cutoff):
        warnings.warn(f"Sa at T = {period:g} s: omega_n = {wn:.3g} rad/s is above half the input's band limit "
                      f"{float(cutoff):.3g} rad/s; the RVT estimate ignores the band limit", UserWarning,
                      stacklevel=2)
    t, v, vd, c = oscillator_covariance(excitation, period, t_end, damping)
    delta = float(oscillator_bandwidth(damping))
    if cutoff is None or wn <= 0.5 * float(cutoff):      # above, the variance ignores the band limit
        delta = max(delta, oscillator_response_bandwidth(excitation, period, damping, cutoff))
    return wn * wn * median_peak(t, v, vd, c, delta)


def oscillator_response_bandwidth(excitation, period, damping=0.05, cutoff=None):
    """Vanmarcke bandwidth of the stationary response of a linear oscillator to the excitation's spectrum.

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        An object with ``psd(omega)`` [m2 s-3] (and ``omega_g``, ``omega_f`` [rad s-1] if it has them).
    period : float
        Natural period [s].
    damping : float, default 0.05
        Damping ratio [1].
    cutoff : float, optional
        Band limit [rad s-1] (``None``: unbounded).

    Returns
    -------
    float
        ``delta`` [1].

    Notes
    -----
    ``delta = sqrt(1 - lambda_1^2 / (lambda_0 lambda_2))`` with the response moments
    ``lambda_i = 2 int_0^omega_c omega^i |H(omega)|^2 S(omega) d omega``,
    ``|H|^2 = 1 / ((omega_n^2 - omega^2)^2 + (2 zeta omega_n omega)^2)``.  Under white noise it is
    :func:`screening.analysis.fragility.oscillator_bandwidth`; under a narrow-band input away from
    ``omega_n`` the response has two spectral peaks (the input's and the resonance) and a larger
    bandwidth.  :func:`sa_median` uses the larger of this and the white-noise bandwidth, and the white-noise
    one alone above half the band limit (``docs/intensity_measures.md``).

    References
    ----------
    [1] [vanmarcke1975].

    Examples
    --------
    Under white noise it is the oscillator's own bandwidth:

    >>> from screening.core.model.excitation import ConstantEnvelope
    >>> from screening.core.excitations.white import WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> from screening.analysis.fragility import oscillator_bandwidth
    >>> f"{oscillator_response_bandwidth(white, 0.5):.6f}", f"{float(oscillator_bandwidth(0.05)):.6f}"
    ('0.245612', '0.245612')
    """
    wn, z = 2.0 * math.pi / float(period), float(damping)
    top = float(cutoff) if cutoff is not None else math.inf
    points = sorted(p for p in (wn, getattr(excitation, "omega_g", None), getattr(excitation, "omega_f", None))
                    if p is not None and np.isfinite(float(p)) and 0.0 < float(p) < top)

    def moment(i):
        def f(w):
            return w**i * float(excitation.psd(w)) / ((wn * wn - w * w) ** 2 + (2.0 * z * wn * w) ** 2)
        if math.isfinite(top):
            return integrate.quad(f, 0.0, top, limit=400, points=points or None, epsabs=0.0, epsrel=1e-10)[0]
        edge = 100.0 * max(points)
        return (integrate.quad(f, 0.0, edge, limit=400, points=points, epsabs=0.0, epsrel=1e-10)[0]
                + integrate.quad(f, edge, math.inf, limit=400, epsabs=0.0, epsrel=1e-10)[0])

    lam0, lam1, lam2 = (moment(i) for i in range(3))
    return math.sqrt(max(1.0 - lam1 * lam1 / (lam0 * lam2), 0.0))


def velocity_spectral_moments(excitation, cutoff, omega_low=OMEGA_LOW):
    """Spectral moments ``(mu_0, mu_1, mu_2)`` of the high-passed ground velocity, band-limited to ``cutoff``.

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        Any object with a method ``psd(omega)``, the two-sided PSD ``S(omega)`` [m2 s-3] of the
        unmodulated acceleration (any excitation: white noise, Kanai-Tajimi, Clough-Penzien, ...).
    cutoff : float
        Band limit ``omega_c`` [rad/s].
    omega_low : float
        Corner of the 2nd-order Butterworth high-pass [rad/s] (default :data:`OMEGA_LOW`, 0.1 Hz).

    Returns
    -------
    tuple of float
        ``mu_0`` [m2 s-2], ``mu_1`` [m2 s-3], ``mu_2`` [m2 s-4].

    Notes
    -----
    ``mu_i = 2 int_0^omega_c omega^i S(omega) |H(omega)|^2 / omega^2 d omega`` with ``|H|^2`` of
    :func:`highpass_gain`: the velocity is the integral of the acceleration, so its PSD is
    ``S(omega) / omega^2``, which is not integrable at ``omega = 0`` when ``S(0) > 0`` (white and
    Kanai-Tajimi noise: their velocity is a random walk of unbounded variance).  The high-pass makes
    the velocity PSD ``S omega^2 / (omega^4 + omega_low^4)``, finite everywhere.  White noise without
    band limit: ``mu_0 = pi S0 / (sqrt(2) omega_low)``.  The high-pass is a 2nd-order Butterworth
    filter as in record processing [1].

    References
    ----------
    [1] [boore2005].

    Examples
    --------
    >>> from screening.core.model.excitation import ConstantEnvelope
    >>> from screening.core.excitations.white import WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> mu0, mu1, mu2 = velocity_spectral_moments(white, 1e5, 0.5)
    >>> import math
    >>> f"{mu0:.5f}", f"{math.pi * 0.01 / (math.sqrt(2) * 0.5):.5f}"
    ('0.04443', '0.04443')
    """
    wc, wl = float(cutoff), float(omega_low)
    points = sorted(p for p in (wl, getattr(excitation, "omega_g", None), getattr(excitation, "omega_f", None))
                    if p is not None and np.isfinite(float(p)) and 0.0 < float(p) < wc)
    out = []
    for i in range(3):
        val, _ = integrate.quad(lambda w: w**i * float(excitation.psd(w)) * w * w / (w**4 + wl**4), 0.0, wc,
                                limit=400, points=points or None, epsrel=1e-11)
        out.append(2.0 * val)
    return tuple(out)


def envelope_exponentials(envelope):
    """The envelope as a sum of exponentials: ``q(t) = sum_j amplitudes_j exp(-rates_j t)``.

    Parameters
    ----------
    envelope : screening.core.model.excitation.Envelope or screening.core.model.excitation.ConstantEnvelope
        The exponential envelope ``4 (exp(-t/T1) - exp(-t/T2))`` or the constant one (``ValueError``
        for another kind).

    Returns
    -------
    tuple of numpy.ndarray
        ``(amplitudes [1], rates [s-1])``.

    Notes
    -----
    The exponential envelope is eq. (57) in [1].

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    >>> from screening.core.model.excitation import Envelope
    >>> amplitudes, rates = envelope_exponentials(Envelope(4.0, 2.0))
    >>> amplitudes.tolist(), rates.tolist()
    ([4.0, -4.0], [0.25, 0.5])
    """
    if envelope.kind == "constant":
        return np.array([1.0]), np.array([0.0])
    if envelope.kind == "exponential":
        return np.array([4.0, -4.0]), np.array([1.0 / float(envelope.T1), 1.0 / float(envelope.T2)])
    raise ValueError(f"envelope kind {envelope.kind!r} has no exponential form (exponential or constant)")


def _low_band_velocity(excitation, t_end, wl, ws, n_times, d_omega):
    """``(t, var_v, var_v_dot, cov)`` of the band ``|omega| <= ws`` by the closed-form evolutionary spectrum
    (:func:`velocity_covariance`)."""
    t = _times(t_end, n_times)
    amps, rates = envelope_exponentials(excitation.envelope)
    r = wl * np.array([-1.0 + 1.0j, -1.0 - 1.0j]) / math.sqrt(2.0)          # poles of G
    c = np.array([r[0] / (r[0] - r[1]), r[1] / (r[1] - r[0])])              # residues of G
    d = -(math.sqrt(2.0) * wl * r + wl * wl) / np.array([r[0] - r[1], r[1] - r[0]])   # of G s - 1
    n_w = max(int(math.ceil(ws / d_omega)), 2)
    omega = np.linspace(0.0, ws, n_w + 1)
    weight = np.full(omega.size, ws / n_w)
    weight[[0, -1]] *= 0.5
    weight *= 2.0 * np.asarray(excitation.psd(omega), dtype=float)          # two-sided: +-omega
    var_v, var_a, cov = np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)
    q = excitation.envelope(t)
    decay = [np.exp(-rate * t) for rate in rates]
    homogeneous = [np.exp(r_k * t) for r_k in r]
    for lo in range(0, omega.size, 200):
        w = omega[lo:lo + 200, None]
        m = np.zeros((w.shape[0], t.size), dtype=complex)
        wave = np.exp(1j * w * t)
        md = q * wave
        for a_j, rate, e_j in zip(amps, rates, decay):
            forced = wave * e_j
            for c_k, d_k, r_k, h_k in zip(c, d, r, homogeneous):
                term = (a_j / (1j * w - rate - r_k)) * (forced - h_k)
                m += c_k * term
                md += d_k * term
        wt = weight[lo:lo + 200, None]
        var_v += np.sum(wt * np.abs(m) ** 2, axis=0)
        var_a += np.sum(wt * np.abs(md) ** 2, axis=0)
        cov += np.sum(wt * (m * np.conj(md)).real, axis=0)
    return t, var_v, var_a, cov


_low_band_velocity_cached = functools.lru_cache(maxsize=256)(_low_band_velocity)


def velocity_covariance(excitation, t_end, cutoff, omega_low=OMEGA_LOW, n_times=1001, d_omega=0.02,
                        split=40.0):
    """The non-stationary moments of the high-passed ground velocity of the modulated input.

    The velocity starts at rest at ``t = 0``.

    Parameters
    ----------
    excitation : screening.core.excitations.base.Excitation
        A registered excitation with ``psd(omega)`` [m2 s-3] and its envelope (exponential or constant).
    t_end : float
        Record length [s].
    cutoff : float
        Band limit [rad s-1].
    omega_low : float, default OMEGA_LOW
        Corner of the 2nd-order Butterworth high-pass [rad s-1].
    n_times : int, default 1001
        Output times over ``[0, t_end]``.
    d_omega : float, default 0.02
        Frequency step of the exact low band [rad s-1].
    split : float, default 40.0
        Top of the exact low band in units of ``omega_low`` [1].

    Returns
    -------
    tuple of numpy.ndarray
        ``(t [s], var_v [m2 s-2], var_v_dot [m2 s-4], cov [m2 s-3])``.

    Notes
    -----
    With ``G(s) = s / (s^2 + sqrt(2) omega_low s + omega_low^2)`` (velocity of the high-passed
    acceleration), its impulse response ``h`` and ``M(t, omega) = int_0^t h(t - s) q(s) e^{i omega s} ds``,
    the velocity of ``a = q f`` has ``var v(t) = int S(omega) |M(t, omega)|^2 d omega`` (Priestley's
    evolutionary spectrum), and ``v' = q f - sqrt(2) omega_low v - omega_low^2 x`` likewise with
    ``dM/dt``.  For ``q = sum_j a_j e^{-t/tau_j}`` and the poles ``r_k`` of ``G`` with residues ``c_k``,
    ``M = sum_j a_j sum_k c_k (e^{p_j t} - e^{r_k t}) / (p_j - r_k)``, ``p_j = i omega - 1/tau_j``:
    exact, on a grid of step ``d_omega`` [rad/s] up to ``split omega_low``.  Above it the velocity is
    local (``M ~ q(t) G(i omega) e^{i omega t}``) and the quasi-stationary moments are used:
    ``q^2 mu_0``, ``q^2 mu_2 + q'^2 mu_0``, ``q q' mu_0`` of that band (:func:`velocity_spectral_moments`).

    References
    ----------
    [1] [priestley1965]; [2] [boore2005].

    Examples
    --------
    Under stationary input, long after the start, the variance is the stationary one of
    :func:`velocity_spectral_moments`:

    >>> from screening.core.model.excitation import ConstantEnvelope
    >>> from screening.core.excitations.white import WhiteNoise
    >>> white = WhiteNoise(0.01, ConstantEnvelope(), band_limit_hz=None)   # S0 = 0.01 m2 s-3, stationary, unbounded
    >>> t, var_v, var_vd, cov = velocity_covariance(white, 60.0, 50.0, omega_low=0.5)
    >>> f"{var_v[-1]:.4f}", f"{velocity_spectral_moments(white, 50.0, 0.5)[0]:.4f}"
    ('0.0440', '0.0440')
    """
    wl, wc = float(omega_low), float(cutoff)
    ws = min(wc, split * wl)
    args = (excitation, float(t_end), wl, ws, int(n_times), float(d_omega))
    try:
        low = _low_band_velocity_cached(*args)
    except TypeError:                                   # an excitation with array fields is not hashable
        low = _low_band_velocity(*args)
    t, var_v, var_a, cov = (x.copy() for x in low)
    q = excitation.envelope(t)
    if wc > ws:
        (h0, _, h2), (l0, _, l2) = velocity_spectral_moments(excitation, wc, wl), \
            velocity_spectral_moments(excitation, ws, wl)
        qd = envelope_rate(excitation.envelope, t)
        var_v += q * q * (h0 - l0)
        var_a += q * q * (h2 - l2) + qd * qd * (h0 - l0)
        cov += q * qd * (h0 - l0)
    return t, var_v, var_a, cov
