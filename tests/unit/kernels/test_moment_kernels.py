"""The compiled moment equations (screening.kernels.moment_kernels) against their numpy reference:
the Lyapunov right-hand side ``A P + P A^T + 2 pi S0 b b^T`` of the augmented system as matrix products."""

import numpy as np
import pytest

from screening.core.excitations import CloughPenzien, KanaiTajimi, WhiteNoise
from screening.kernels.moment_kernels import (augmented_rhs, augmented_rhs_two_states, augmented_system,
                                              lyapunov_rhs, packed_size)

EXCITATIONS = [WhiteNoise(2e-4), KanaiTajimi(2e-4, 15.0, 0.6), CloughPenzien(2e-4, 15.0, 0.6, 1.5, 0.8)]


@pytest.mark.parametrize("exc", EXCITATIONS, ids=lambda e: e.kind)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_compiled_rhs_is_the_matrix_product_reference(exc, seed):
    rng = np.random.default_rng(seed)
    filt = exc.filter()
    n = np.shape(filt.A)[-1] + 2
    root = rng.normal(size=(n, n)) * np.logspace(-3, 0, n)
    P = root @ root.T                                         # a covariance (symmetric, positive)
    k_eq, c_eq, m_sdof, alpha = rng.uniform(10.0, 100.0), rng.uniform(0.01, 0.5), rng.uniform(0.1, 1.0), 3.7
    A, b = augmented_system(k_eq, c_eq, m_sdof, alpha, filt)
    expected = lyapunov_rhs(P, A, b, exc.S0)
    iu = np.triu_indices(n)
    y = np.ascontiguousarray(P[iu])
    dy = np.empty(packed_size(n))
    fa, fb, fc = (np.ascontiguousarray(m, dtype=float) for m in filt[:3])
    augmented_rhs(k_eq / m_sdof, c_eq / m_sdof, alpha, 2.0 * np.pi * exc.S0, fa, fb, fc, float(filt.D), y, dy,
                  np.empty((n, n)), np.empty((n, n)))
    np.testing.assert_allclose(dy, expected[iu], rtol=1e-12, atol=1e-13 * np.abs(expected).max())
    np.testing.assert_allclose(expected, expected.T, rtol=1e-14, atol=1e-15 * np.abs(expected).max())
    if n == 4:                                                # the written-out two-state twin
        dy2 = np.empty(packed_size(n))
        augmented_rhs_two_states(k_eq / m_sdof, c_eq / m_sdof, alpha, 2.0 * np.pi * exc.S0, fa, fb, fc,
                                 float(filt.D), y, dy2)
        np.testing.assert_allclose(dy2, expected[iu], rtol=1e-12, atol=1e-13 * np.abs(expected).max())


@pytest.mark.parametrize("exc", EXCITATIONS[1:], ids=lambda e: e.kind)
def test_filter_block_of_the_reference_vanishes_at_the_stationary_covariance(exc):
    """The filter rows of the Lyapunov right-hand side are zero at the filter's stationary covariance
    (whatever the oscillator does: the filter does not feel it)."""
    filt = exc.filter()
    nf = np.shape(filt.A)[-1]
    A, b = augmented_system(50.0, 0.1, 0.5, 2.0, filt)
    P = np.eye(nf + 2) * 1e-6
    P[2:, 2:] = exc.stationary_covariance()
    rhs = lyapunov_rhs(P, A, b, exc.S0)
    np.testing.assert_allclose(rhs[2:, 2:], 0.0, atol=1e-12 * np.abs(P[2:, 2:]).max() * np.abs(filt.A).max())


def test_white_noise_fast_path_is_the_reference_without_filter_states():
    """The 3-moment loop's right-hand side (eq. 45) is the reference with ``n_f = 0``, ``D = 1``."""
    from screening.core import condensation
    from screening.core.condensation.uplift_integrals import coefficient_table
    from screening.core.model import Block, Foundation
    from screening.core.model.points import flatten
    from screening.kernels.moment_kernels import _white_rhs

    exc = WhiteNoise(3e-4, band_limit_hz=None)                  # no filter states: the 3-moment loop
    (block, bed), _ = flatten(Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8, eps=6e7))
    kernel = condensation.get("paper").moment_kernel(block, bed)
    table = coefficient_table()
    m_sdof, alpha = float(block.m_sdof[0]), 2.3
    y = (2e-5, 1e-4, 0.3)                                     # var_theta, cov, var_theta_dot
    *dy, c_eq, k_eq = _white_rhs(kernel.coefficients, kernel.records[0], table, 1.0 / m_sdof, exc.S0, alpha, *y)
    assert (c_eq, k_eq) == kernel.coefficients(kernel.records[0], table, y[0], y[1])
    A, b = augmented_system(k_eq, c_eq, m_sdof, alpha, exc.filter())
    expected = lyapunov_rhs(np.array([[y[0], y[1]], [y[1], y[2]]]), A, b, exc.S0)
    np.testing.assert_allclose(dy, expected[np.triu_indices(2)], rtol=1e-12)


def test_the_uplift_occupancy_is_the_gaussian_tail_beyond_the_uplift_angle_in_both_twins():
    """eq. 58 three ways: the numpy reference, its compiled twin and a quadrature of the Gaussian density;
    0 for a variance that is not positive; the condensation API's closed form agrees."""
    from scipy import integrate

    from screening.core.condensation.api import uplift_probability
    from screening.core.model import Block, Foundation
    from screening.kernels.moment_kernels import p_uplift, uplift_occupancy

    theta_ul, record = 2e-4, np.zeros(1, dtype=[("theta_ul", "f8")])
    record["theta_ul"] = theta_ul
    for var in (1e-9, 4e-8, 1e-6):
        sigma = np.sqrt(var)
        tail = 2 * integrate.quad(lambda x: np.exp(-x * x / (2 * var)) / (sigma * np.sqrt(2 * np.pi)), theta_ul,
                                  theta_ul + 40 * sigma, epsabs=0, epsrel=1e-12)[0]
        reference = float(uplift_occupancy(theta_ul, var))
        assert reference == pytest.approx(tail, rel=1e-8)
        assert p_uplift(record[0], var) == pytest.approx(reference, rel=1e-14)
    np.testing.assert_array_equal(uplift_occupancy(theta_ul, np.array([0.0, -1.0])), [0.0, 0.0])
    assert p_uplift(record[0], 0.0) == 0.0
    block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8)
    tu = float(block.m * block.g / (2 * block.b**2 * bed.k))
    assert float(uplift_probability(np.sqrt(4e-8), block, bed)) == pytest.approx(float(uplift_occupancy(tu, 4e-8)),
                                                                                 rel=1e-12)


def _random_covariance(rng, scales):
    """A random covariance with standard deviations ``scales`` (a random correlation matrix between them)."""
    root = rng.normal(size=(scales.size, scales.size))
    cov = root @ root.T
    d = np.sqrt(np.diag(cov))
    return cov / np.outer(d, d) * np.outer(scales, scales)


@pytest.mark.parametrize("condensation", ["paper", "cubic"])
@pytest.mark.parametrize("exc", EXCITATIONS, ids=lambda e: e.kind)
def test_compiled_right_hand_side_at_its_coefficients_is_the_numpy_moment_equations(exc, condensation):
    """The right-hand side the compiled loops integrate (coefficients from the condensation's compiled
    function, Lyapunov products written out) against :func:`moment_equations` (coefficients from the
    condensation's numpy functions, matrix products) on random states from no uplift to heavy uplift, at
    a time inside the envelope's rise."""
    from screening.core import condensation as condensations
    from screening.core.model import Block, Foundation
    from screening.core.model.points import flatten
    from screening.kernels.moment_kernels import _filtered_rhs, _white_rhs, moment_equations
    from screening.solvers.moments import oscillator_records

    block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
    cond = condensations.get(condensation)
    (fb, ff, fe), _ = flatten(block, bed, exc)
    kernel = cond.moment_kernel(fb, ff)
    osc = oscillator_records(fb, ff, fe, cond)[0]
    table = kernel.tables[kernel.table_index[0]]
    filt = exc.filter()
    nf = np.shape(filt.A)[-1]
    fa, fbm, fc = (np.ascontiguousarray(m, dtype=float) for m in filt[:3])
    t = 1.3
    alpha = osc["gain"] * exc.envelope(t)
    tu, w = float(osc["theta_ul"]), np.sqrt(osc["k_rest"] / osc["m_sdof"])
    filter_sd = np.sqrt(np.diag(exc.stationary_covariance())) if nf else np.zeros(0)
    rng = np.random.default_rng(7)
    for ratio in (0.1, 1.0, 3.0, 10.0):                       # sigma_theta / theta_ul
        s = ratio * tu
        P = _random_covariance(rng, np.concatenate([[s, s * w], filter_sd]))
        expected = moment_equations(t, P, block, bed, exc, condensation)
        iu = np.triu_indices(nf + 2)
        if nf == 0:
            *dy, _, _ = _white_rhs(kernel.coefficients, kernel.records[0], table, 1.0 / osc["m_sdof"], osc["S0"],
                                   alpha, P[0, 0], P[0, 1], P[1, 1])
        else:
            dy = np.empty(packed_size(nf + 2))
            _filtered_rhs(dy.size, kernel.coefficients, kernel.records[0], table, osc, fa, fbm, fc, float(filt.D),
                          alpha, np.ascontiguousarray(P[iu]), dy, np.empty((nf + 2,) * 2), np.empty((nf + 2,) * 2))
        # the compiled coefficients interpolate tables (closed form: 1e-9; quadrature: 1e-6 relative)
        tol = 1e-7 if condensation == "paper" else 1e-5
        np.testing.assert_allclose(dy, expected[iu], rtol=tol, atol=tol * np.abs(expected).max())


@pytest.mark.parametrize("exc", [WhiteNoise(4e-4), KanaiTajimi(4e-4, 15.0, 0.6), CloughPenzien(4e-4, 15.0, 0.6, 1.5, 0.8)],
                         ids=lambda e: e.kind)
def test_the_compiled_solver_follows_an_independent_integration_of_the_moment_equations(exc):
    """The whole compiled solver (step loop, envelope gains, dense output) against scipy's ``solve_ivp``
    (DOP853, tight tolerances) of the numpy :func:`moment_equations`, through the onset of uplift (the
    coefficients change along the way: the equations are nonlinear) and the envelope's peak (t = 2.8 s), on
    4 s (the numpy right-hand side costs ~1 ms a call: 8 s took 20 s of CPU for the three inputs)."""
    from scipy import integrate

    from screening.core.model import Block, Foundation
    from screening.kernels.moment_kernels import moment_equations
    from screening.solvers.moments import solve_moments
    from screening.solvers.timegrid import output_times

    block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
    t_out = output_times(4.0, 0.25)
    res = solve_moments(block, bed, exc, t_out, rtol=1e-10)
    n = np.shape(exc.filter().A)[-1] + 2
    iu = np.triu_indices(n)

    def rhs(t, y):
        P = np.zeros((n, n))
        P[iu] = y
        P = P + np.triu(P, 1).T
        return moment_equations(t, P, block, bed, exc)[iu]

    # absolute tolerances from each entry's size: the peak rocking moments, the filter's stationary ones
    sizes = np.concatenate([[res["var_theta"].max(), res["var_theta_dot"].max()],
                            np.diag(exc.stationary_covariance()) if n > 2 else []])
    atol = 1e-10 * np.sqrt(sizes[iu[0]] * sizes[iu[1]])
    ref = integrate.solve_ivp(rhs, (0.0, t_out[-1]), np.zeros(iu[0].size), method="DOP853", t_eval=t_out,
                              rtol=1e-10, atol=atol)
    assert ref.success
    var_theta = ref.y[0]
    assert res["p_uplift"].max() > 0.1                        # uplift is reached: the coefficients move
    np.testing.assert_allclose(res["var_theta"], var_theta, rtol=1e-6, atol=1e-6 * var_theta.max())
    np.testing.assert_allclose(res["var_theta_dot"], ref.y[n], rtol=1e-6, atol=1e-6 * ref.y[n].max())
