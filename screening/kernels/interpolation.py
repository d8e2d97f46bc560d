"""Cubic Hermite interpolation, shared by every compiled table lookup and by the Monte Carlo input
(:mod:`screening.condensation.uplift_integrals`, :mod:`screening.condensation.quadrature`,
:mod:`screening.solvers.mcs_kernels`)."""

import numba


@numba.njit(cache=True, inline="always")
def hermite(v0, v1, d0, d1, s, step):
    """Cubic Hermite interpolant at fraction ``s`` of a node interval of length ``step``.

    ``v0``, ``v1``: values at the two nodes; ``d0``, ``d1``: their derivatives (per unit of the
    variable whose interval is ``step``).
    """
    s2 = s * s
    s3 = s2 * s
    return ((2.0 * s3 - 3.0 * s2 + 1.0) * v0 + (-2.0 * s3 + 3.0 * s2) * v1
            + step * ((s3 - 2.0 * s2 + s) * d0 + (s3 - s2) * d1))
