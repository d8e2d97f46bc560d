"""Numba types of the functions a condensation hands to the compiled solvers.

A condensation's compiled functions take its own parameter record (a numpy structured dtype,
one record per parameter point) and are passed to the solvers as first-class functions with
these explicit signatures, so the solvers are compiled once per record type and cached (a
closure or a dispatcher argument would never hit numba's cache).
"""

from __future__ import annotations

import numba
from numba import types

#: Floating-point flags of the moment solver's step loops and the coefficient functions they call:
#: LLVM may fuse a multiply and an add into one FMA instruction where the CPU has one (shorter
#: latency per Runge-Kutta stage, about 10 % less time per step; results change at rounding level,
#: ~1e-13 of peak var_theta).  No other fast-math assumption: NaN and inf keep their meaning.
FMA = {"contract"}

FLOAT = types.float64
TABLE = types.float64[:, ::1]   # per-interval cubic coefficients (screening.kernels.interpolation)


def record_type(dtype):
    """The numba type of one record of the structured ``dtype``."""
    return numba.from_dtype(dtype)


def moment_coefficients_signature(dtype):
    """``(record, table, var_theta [rad2], cov [rad2/s]) -> (c_eq [N m s/rad], k_eq [N m/rad])``."""
    return types.UniTuple(FLOAT, 2)(record_type(dtype), TABLE, FLOAT, FLOAT)


def sdof_coefficients_signature(dtype):
    """``(record, theta [rad]) -> (C(theta) [N m s/rad], K(theta) [N m/rad])``."""
    return types.UniTuple(FLOAT, 2)(record_type(dtype), FLOAT)


def function_type(signature):
    """The first-class function type of a compiled function with ``signature``."""
    return types.FunctionType(signature)
