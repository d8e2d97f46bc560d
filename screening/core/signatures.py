"""Numba types of the functions a condensation hands to the compiled solvers, and the records that carry them.

The functions take the condensation's own structured parameter record and are passed as first-class
functions with explicit signatures, so the solvers compile once per record type and hit numba's cache.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np
from numba import types

__all__ = []

#: Floating-point flags of the moment solver's step loops and the coefficient functions they call:
#: LLVM may fuse a multiply and an add into one FMA instruction where the CPU has one (shorter
#: latency per Runge-Kutta stage, about 10 % less time per step; results change at rounding level,
#: ~1e-13 of peak var_theta).  No other fast-math assumption: NaN and inf keep their meaning.
FMA = {"contract"}

FLOAT = types.float64
TABLE = types.float64[:, ::1]   # per-interval cubic coefficients (screening.core.interpolation)


def record_type(dtype):
    """The numba record type of a structured dtype of float fields [SI]."""
    return numba.from_dtype(dtype)


def moment_coefficients_signature(dtype):
    """Signature ``(record, table, var_theta [rad2], cov [rad2/s]) -> (c_eq [N m s/rad], k_eq [N m/rad])`` of a condensation's compiled coefficients (table: C-contiguous 2-d float64)."""
    return types.UniTuple(FLOAT, 2)(record_type(dtype), TABLE, FLOAT, FLOAT)


def sdof_coefficients_signature(dtype):
    """Signature ``(record, theta [rad]) -> (C(theta) [N m s/rad], K(theta) [N m/rad])`` of a condensation's compiled damping and stiffness."""
    return types.UniTuple(FLOAT, 2)(record_type(dtype), FLOAT)


def function_type(signature):
    """The first-class function type a solver declares for a compiled function of ``signature``."""
    return types.FunctionType(signature)


class SdofKernel(NamedTuple):
    """What the compiled Monte Carlo integrator needs of a condensation (condensed model).

    ``damping_stiffness``: compiled ``(record, theta) -> (C, K)`` (signature
    :func:`screening.core.signatures.sdof_coefficients_signature`); ``record``: a 1-element
    structured array of its parameters.
    """

    damping_stiffness: object
    record: np.ndarray


class MomentKernel(NamedTuple):
    """What the compiled moment solver needs of a condensation, for a batch of points.

    ``coefficients``: compiled ``(record, table, var_theta, cov) -> (c_eq, k_eq)``
    (signature :func:`screening.core.signatures.moment_coefficients_signature`); ``records``: one
    structured record per point; ``tables``: ``(n_tables, rows, columns)``, each a table of
    per-interval cubic coefficients (:func:`screening.core.interpolation.cubic_coefficients`);
    ``table_index``: the table of each point.
    """

    coefficients: object
    records: np.ndarray
    tables: np.ndarray
    table_index: np.ndarray
