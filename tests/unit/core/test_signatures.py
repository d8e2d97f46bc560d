"""Numba types of the functions a condensation hands to the solvers (screening.core.signatures)."""

import numba
import numpy as np
import pytest

from screening.core import signatures as sig

RECORD = np.dtype([("a", "f8"), ("b", "f8")])


def test_a_function_compiled_with_the_sdof_signature_takes_a_record_and_returns_c_and_k():
    @numba.njit(sig.sdof_coefficients_signature(RECORD))
    def damping_stiffness(p, theta):
        return p["a"] * theta, p["b"]

    rec = np.array([(2.0, 3.0)], dtype=RECORD)
    assert damping_stiffness(rec[0], 0.5) == (1.0, 3.0)
    assert damping_stiffness.nopython_signatures[0] == sig.sdof_coefficients_signature(RECORD)


def test_a_function_compiled_with_the_moment_signature_passes_as_a_first_class_function():
    @numba.njit(sig.moment_coefficients_signature(RECORD))
    def coefficients(p, table, var_theta, cov):
        return p["a"] + table[0, 0], var_theta + cov

    @numba.njit
    def call(f, rec, table):
        return f(rec, table, 1.0, 2.0)

    rec = np.array([(1.0, 0.0)], dtype=RECORD)
    table = np.full((2, 4), 0.5)
    assert call(coefficients, rec[0], table) == (1.5, 3.0)
    ftype = sig.function_type(sig.moment_coefficients_signature(RECORD))
    assert isinstance(ftype, numba.types.FunctionType)


def test_the_kernel_records_are_the_ones_the_condensations_use():
    from screening.core.condensation import base

    assert base.MomentKernel is sig.MomentKernel and base.SdofKernel is sig.SdofKernel
    assert sig.MomentKernel._fields == ("coefficients", "records", "tables", "table_index")
    assert sig.SdofKernel._fields == ("damping_stiffness", "record")
    with pytest.raises(TypeError):
        sig.SdofKernel(None)                               # both fields are required
