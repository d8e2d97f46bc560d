"""Cubic Hermite interpolation: one basis, shared by every compiled table lookup and by the Monte Carlo
input (:mod:`screening.condensation.uplift_integrals`, :mod:`screening.condensation.quadrature`,
:mod:`screening.solvers.mcs_kernels`)."""

import numba


@numba.njit(cache=True, inline="always")
def hermite_weights(s):
    """Cubic Hermite weights ``(h00, h10, h01, h11)`` at fraction ``s`` of a node interval.

    The interpolant is ``h00 v0 + h01 v1 + step (h10 d0 + h11 d1)`` for values ``v`` and
    derivatives ``d`` at the two nodes of an interval of length ``step``.
    """
    s2 = s * s
    s3 = s2 * s
    return 2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, -2.0 * s3 + 3.0 * s2, s3 - s2


@numba.njit(cache=True, inline="always")
def hermite(v0, v1, d0, d1, s, step):
    """Cubic Hermite interpolant at fraction ``s`` of an interval of length ``step`` (values ``v0``,
    ``v1`` and derivatives ``d0``, ``d1`` at its nodes)."""
    h00, h10, h01, h11 = hermite_weights(s)
    return h00 * v0 + h01 * v1 + step * (h10 * d0 + h11 * d1)
