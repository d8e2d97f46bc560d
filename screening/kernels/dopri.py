"""The embedded Dormand–Prince 5(4) pair shared by every compiled integrator of the package.

One home for the tableau (Hairer, Norsett & Wanner, *Solving ODEs I*, table II.5.2; the same as
scipy's ``RK45``), its 4th-order dense output, and the PI step-size controller of Hairer's
DOPRI5 (``alpha = 0.17``, ``beta = 0.04``: smooth near the stability bound).  The moment solver
(:mod:`screening.solvers.moments`, arrays of 3 or 10 moments) and the Monte Carlo integrator
(:mod:`screening.kernels.mcs_kernels`, 4 scalar states) run their step loops on these.

Symbols: ``h`` step [s], stage ``s`` at time ``t + C[s] h``; ``y_new = y + h sum_s B[s] K[s]``;
error estimate ``h sum_s E[s] K[s]`` (5th minus 4th order, FSAL stage 7 included).

Method and how it is checked: ``docs/method.md#moment-solver``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = []

#: Stage coefficients a_sq (rows: stages 2..6).
A = np.array([
    [0.0, 0, 0, 0, 0],
    [1 / 5, 0, 0, 0, 0],
    [3 / 40, 9 / 40, 0, 0, 0],
    [44 / 45, -56 / 15, 32 / 9, 0, 0],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
])
#: Stage times c_s (7 stages, the last one FSAL at t + h).
C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
#: 5th-order weights.
B = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84])
#: Error weights (5th minus 4th order).
E = np.array([-71 / 57600, 0.0, 71 / 16695, -71 / 1920, 17253 / 339200, -22 / 525, 1 / 40])
#: Dense output: coefficients of theta, theta^2, theta^3, theta^4 per stage.
P = np.array([
    [1, -8048581381 / 2820520608, 8663915743 / 2820520608, -12715105075 / 11282082432],
    [0, 0, 0, 0],
    [0, 131558114200 / 32700410799, -68118460800 / 10900136933, 87487479700 / 32700410799],
    [0, -1754552775 / 470086768, 14199869525 / 1410260304, -10690763975 / 1880347072],
    [0, 127303824393 / 49829197408, -318862633887 / 49829197408, 701980252875 / 199316789632],
    [0, -282668133 / 205662961, 2019193451 / 616988883, -1453857185 / 822651844],
    [0, 40617522 / 29380423, -110615467 / 29380423, 69997945 / 29380423],
])

#: Step-size factor bounds and safety factor of the controller.
FAC_MIN, FAC_MAX, SAFETY = 0.2, 5.0, 0.9
#: PI exponents (Hairer's DOPRI5): ``fac = SAFETY err^-ALPHA err_old^BETA``.
ALPHA, BETA = 0.17, 0.04
#: Exponent of the plain (I) controller after a rejected step: ``err^-1/5``.
REJECT_EXPONENT = 0.2
#: Logarithm of the "previous" error norm before the first step, and the floor of the error norm
#: the controller sees.
LOG_ERR_START = math.log(1e-4)
ERR_FLOOR = 1e-10


@numba.njit(cache=True, inline="always")
def dense_output(y0, K, h, theta, j):
    """Component ``j`` of the dense-output polynomial at fraction ``theta`` of the step ``h``.

    Parameters
    ----------
    y0 : numpy.ndarray
        State at the start of the step.
    K : numpy.ndarray
        The 7 stage derivatives (rows), one column per component.
    h : float
        Step size [s].
    theta : float
        Fraction of the step [1], in [0, 1].
    j : int
        Component.

    Returns
    -------
    float
        ``y_j(t + theta h)`` of the 4th-order continuous extension.

    Notes
    -----
    ``y(t + theta h) = y0 + h sum_i K_i theta (P_i0 + theta (P_i1 + theta (P_i2 + theta P_i3)))`` with the
    dense-output coefficients :data:`P` of the pair [2]; exact at both ends of the step.

    References
    ----------
    .. [1] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    """
    acc = 0.0
    for i in range(7):
        q = theta * (P[i, 0] + theta * (P[i, 1] + theta * (P[i, 2] + theta * P[i, 3])))
        acc += K[i, j] * q
    return y0[j] + h * acc


@numba.njit(cache=True, inline="always")
def rejected_step_factor(err):
    """Step factor after a rejected step.

    Parameters
    ----------
    err : float
        Error norm [1], > 1.

    Returns
    -------
    float
        ``max(FAC_MIN, SAFETY err^(-1/5))`` [1].

    Notes
    -----
    The plain (I) controller of a 5th-order pair after a rejection [2].

    References
    ----------
    .. [1] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    """
    return max(FAC_MIN, SAFETY * err**-REJECT_EXPONENT)


@numba.njit(cache=True, inline="always")
def accepted_step_factor(err, err_old):
    """PI step factor after an accepted step.

    Parameters
    ----------
    err : float
        Current error norm [1].
    err_old : float
        Previous error norm [1].

    Returns
    -------
    float
        ``SAFETY err^-ALPHA err_old^BETA`` [1], within ``[FAC_MIN, FAC_MAX]``.

    Notes
    -----
    The PI controller of Hairer's DOPRI5 [2] (exponents :data:`ALPHA`, :data:`BETA`).

    References
    ----------
    .. [1] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    """
    return min(FAC_MAX, max(FAC_MIN, SAFETY * err**-ALPHA * err_old**BETA))


@numba.njit(cache=True, inline="always")
def accepted_step_factor_log(log_err, log_err_old):
    """:func:`accepted_step_factor` from the logarithms of the error norms.

    Parameters
    ----------
    log_err : float
        ``ln`` of the current error norm.
    log_err_old : float
        ``ln`` of the previous error norm.

    Returns
    -------
    float
        The PI step factor [1].

    Notes
    -----
    The scalar integrators' form of the PI controller of [2]: one ``exp`` per step.

    References
    ----------
    .. [1] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    """
    return min(FAC_MAX, max(FAC_MIN, SAFETY * math.exp(-ALPHA * log_err + BETA * log_err_old)))


@numba.njit(cache=True, inline="always")
def pi_step_factor(err, log_err_old):
    """The PI step factor after an accepted step, and the logarithm to carry to the next.

    Parameters
    ----------
    err : float
        Error norm of the accepted step [1].
    log_err_old : float
        ``ln`` of the previous error norm.

    Returns
    -------
    factor : float
        The PI step factor [1] of :func:`accepted_step_factor_log`.
    log_err : float
        ``ln max(err, ERR_FLOOR)``, the next step's ``log_err_old``.

    Notes
    -----
    The PI controller of [2]; the error norm is floored at :data:`ERR_FLOOR`.

    References
    ----------
    .. [1] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    """
    log_err = math.log(max(err, ERR_FLOOR))
    return accepted_step_factor_log(log_err, log_err_old), log_err


@numba.njit(cache=True, inline="always")
def rejected_step_factor_log(log_err):
    """:func:`rejected_step_factor` from the logarithm of the error norm.

    Parameters
    ----------
    log_err : float
        ``ln`` of the error norm (> 0: the step was rejected).

    Returns
    -------
    float
        ``max(FAC_MIN, SAFETY exp(-log_err / 5))`` [1].

    Notes
    -----
    The scalar integrators' form of the I controller of [2].

    References
    ----------
    .. [1] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    """
    return max(FAC_MIN, SAFETY * math.exp(-REJECT_EXPONENT * log_err))


# Scalar forms of the tableau for the scalar-locals integrators (stage ``s`` = 1..7, zero entries
# omitted): ``A<s><q>``, ``B<q>``, ``E<q>``, ``C<s>``.
C2, C3, C4, C5 = (float(c) for c in C[1:5])
A21 = float(A[1, 0])
A31, A32 = (float(a) for a in A[2, :2])
A41, A42, A43 = (float(a) for a in A[3, :3])
A51, A52, A53, A54 = (float(a) for a in A[4, :4])
A61, A62, A63, A64, A65 = (float(a) for a in A[5, :5])
B1, B3, B4, B5, B6 = (float(B[i]) for i in (0, 2, 3, 4, 5))
E1, E3, E4, E5, E6, E7 = (float(E[i]) for i in (0, 2, 3, 4, 5, 6))
_P = [[float(v) for v in row] for row in P]
(P10, P11, P12, P13), (P30, P31, P32, P33), (P40, P41, P42, P43), (P50, P51, P52, P53), \
    (P60, P61, P62, P63), (P70, P71, P72, P73) = (_P[i] for i in (0, 2, 3, 4, 5, 6))


@numba.njit(cache=True, inline="always")
def dense_weights(theta):
    """Weights of the nonzero stages in :func:`dense_output` at fraction ``theta`` of a step.

    Parameters
    ----------
    theta : float
        Fraction of the step [1], in [0, 1].

    Returns
    -------
    tuple of float
        ``(w1, w3, w4, w5, w6, w7)`` [1]: ``y(t + theta h) = y0 + h (K1 w1 + K3 w3 + K4 w4 + K5 w5 + K6 w6 + K7 w7)``.

    Notes
    -----
    Bit for bit the value of :func:`dense_output` (same products and sums; stage 2 has zero weight); one
    set of weights serves every component.  At ``theta = 1`` they are the 5th-order weights :data:`B` [1].

    References
    ----------
    .. [1] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    """
    return (theta * (P10 + theta * (P11 + theta * (P12 + theta * P13))),
            theta * (P30 + theta * (P31 + theta * (P32 + theta * P33))),
            theta * (P40 + theta * (P41 + theta * (P42 + theta * P43))),
            theta * (P50 + theta * (P51 + theta * (P52 + theta * P53))),
            theta * (P60 + theta * (P61 + theta * (P62 + theta * P63))),
            theta * (P70 + theta * (P71 + theta * (P72 + theta * P73))))


@numba.njit(cache=True, inline="always")
def dense_value(y0, k, h, theta):
    """One component of the dense output at fraction ``theta`` of a step.

    Parameters
    ----------
    y0 : float
        The component at the start of the step.
    k : tuple of float
        ``(K1, K3, K4, K5, K6, K7)``: its nonzero-weight stage derivatives.
    h : float
        Step size [s].
    theta : float
        Fraction of the step [1], in [0, 1].

    Returns
    -------
    float
        The component at ``t + theta h``.

    Notes
    -----
    :func:`dense_output` on scalars, with :func:`dense_weights` [2].

    References
    ----------
    .. [1] [dormand1980] in the bibliography, ``docs/bibliography.md``.
    .. [2] [hairer1993] in the bibliography, ``docs/bibliography.md``.
    """
    w1, w3, w4, w5, w6, w7 = dense_weights(theta)
    return y0 + h * (k[0] * w1 + k[1] * w3 + k[2] * w4 + k[3] * w5 + k[4] * w6 + k[5] * w7)


# ----------------------------------------------------------------------------- linear stability (Python)
def stability_function(z):
    """Stability function ``R(z) = 1 + z b^T (I - z A)^-1 1`` of the 5th-order solution [1].

    One step of the pair on ``y' = lambda y`` multiplies ``y`` by ``R(h lambda)``; ``z = h lambda``
    (complex, scalar or array).  A polynomial of degree 6 (six stages; the FSAL stage does not enter
    the solution).
    """
    a = np.pad(A, ((0, 0), (0, 1)))               # the six stages of the solution, square
    z = np.asarray(z, dtype=complex)
    out = np.empty(z.shape, dtype=complex)
    ones = np.ones(6)
    for idx, zi in np.ndenumerate(z):
        out[idx] = 1.0 + zi * (B @ np.linalg.solve(np.eye(6) - zi * a, ones))
    return out[()] if out.ndim == 0 else out


def stability_bound(zeta, r_max=10.0, n_grid=20_000):
    """Largest ``h w`` [1] for which a step of the pair is stable on a linear mode of natural frequency
    ``w`` and damping ratio ``zeta >= 0``: the first ``|h lambda|`` along the mode's eigenvalue at which
    ``|R(h lambda)|`` exceeds 1, divided by ``|lambda| / w``.

    Notes
    -----
    Underdamped (``zeta < 1``): ``lambda = w (-zeta + i sqrt(1 - zeta^2))``, ``|lambda| = w``.
    Overdamped: the fast root ``lambda = -w (zeta + sqrt(zeta^2 - 1))`` bounds the step.  The ray is
    scanned on ``n_grid`` points up to ``r_max`` and the crossing refined by bisection; ``inf`` if
    none.  Above this ``h w`` an explicit step is held by stability, below it by accuracy.
    """
    zeta = float(zeta)
    if zeta < 1.0:
        direction, magnitude = complex(-zeta, math.sqrt(1.0 - zeta * zeta)), 1.0
    else:
        direction, magnitude = -1.0 + 0j, zeta + math.sqrt(zeta * zeta - 1.0)
    r = np.linspace(r_max / n_grid, r_max, n_grid)
    unstable = np.abs(stability_function(r * direction)) > 1.0
    if not unstable.any():
        return math.inf
    i = int(np.argmax(unstable))
    lo, hi = (r[i - 1] if i > 0 else 0.0), r[i]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if abs(stability_function(mid * direction)) <= 1.0 else (lo, mid)
    return lo / magnitude
