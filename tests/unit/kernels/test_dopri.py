"""The Dormand-Prince 5(4) tableau, its step controller and dense output (screening.kernels.dopri)."""

import numpy as np
import pytest

from screening.kernels import dopri


def test_the_tableau_meets_the_order_conditions():
    """Row sums of A are C; the weights B integrate c^q exactly to order 5; E (= B - B_hat) has weight 0
    and the embedded solution is of order 4 (it integrates c^q to q = 3 but not the fifth-order terms)."""
    A, B, C, E = dopri.A, dopri.B, dopri.C, dopri.E
    np.testing.assert_allclose(A.sum(axis=1)[:6], C[:6], rtol=0, atol=1e-15)
    for q in range(5):
        assert B @ C[:6] ** q == pytest.approx(1.0 / (q + 1), rel=1e-14)
    assert B @ (A @ C[:5]) == pytest.approx(1.0 / 6.0, rel=1e-14)          # A: stages 1..6 x columns 1..5
    b_hat = np.append(B, 0.0) - E
    assert E.sum() == pytest.approx(0.0, abs=1e-16) and b_hat.sum() == pytest.approx(1.0, rel=1e-14)
    for q in range(4):
        assert b_hat @ C ** q == pytest.approx(1.0 / (q + 1), rel=1e-13)


def test_the_scalar_forms_are_the_tableau():
    assert (dopri.A31, dopri.A65, dopri.B1, dopri.B6, dopri.E7) == (dopri.A[2, 0], dopri.A[5, 4], dopri.B[0],
                                                                     dopri.B[5], dopri.E[6])


def test_dense_output_is_exact_for_a_polynomial_and_its_weights_match_the_array_form():
    """y' = 4 t^3 from y(0) = 0 with h = 1: the stages are 4 c^3 and the dense output reproduces
    y(theta) = theta^4 (a fourth-degree interpolant exact for this quartic)."""
    K = (4.0 * dopri.C ** 3)[:, None]
    for theta in (0.0, 0.3, 0.7, 1.0):
        value = dopri.dense_output.py_func(np.zeros(1), K, 1.0, theta, 0)
        assert value == pytest.approx(theta**4, abs=1e-13)
        w = dopri.dense_weights.py_func(theta)
        nonzero = K[[0, 2, 3, 4, 5, 6], 0]
        assert float(np.dot(w, nonzero)) == pytest.approx(value, abs=1e-15)
    np.testing.assert_allclose(dopri.dense_weights.py_func(1.0), np.append(dopri.B, 0.0)[[0, 2, 3, 4, 5, 6]],
                               atol=1e-15)


def test_the_step_factors_shrink_after_large_errors_and_are_clipped():
    assert dopri.rejected_step_factor.py_func(1e6) == dopri.FAC_MIN
    assert dopri.rejected_step_factor.py_func(1.5) < 1.0
    assert dopri.accepted_step_factor.py_func(1e-12, 1e-12) <= dopri.FAC_MAX
    small, large = (dopri.accepted_step_factor.py_func(e, 0.5) for e in (0.01, 0.9))
    assert small > large
    log_form = dopri.accepted_step_factor_log.py_func(np.log(0.3), np.log(0.5))
    assert log_form == pytest.approx(dopri.accepted_step_factor.py_func(0.3, 0.5), rel=1e-12)
    factor, log_err = dopri.pi_step_factor.py_func(0.3, np.log(0.5))
    assert factor == pytest.approx(log_form, rel=1e-12) and log_err == pytest.approx(np.log(0.3))
    assert dopri.rejected_step_factor_log.py_func(np.log(1.5)) == pytest.approx(
        dopri.rejected_step_factor.py_func(1.5), rel=1e-12)
