"""Cubic Hermite interpolation weights, shared by the compiled coefficient tables
(:mod:`screening.condensation.uplift_integrals`, :mod:`screening.condensation.quadrature`)."""

import numba


@numba.njit(cache=True, inline="always")
def hermite_basis(s, step):
    """Cubic Hermite weights ``(h00, h10, h01, h11)`` at fraction ``s`` of a node interval of
    length ``step`` (``h10``, ``h11`` multiply the slopes, so they carry the ``step``)."""
    s2 = s * s
    s3 = s2 * s
    return (2.0 * s3 - 3.0 * s2 + 1.0, (s3 - 2.0 * s2 + s) * step,
            -2.0 * s3 + 3.0 * s2, (s3 - s2) * step)
