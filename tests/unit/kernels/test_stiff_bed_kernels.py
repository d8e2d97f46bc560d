"""The stiff-bed model's compiled integrator (screening.kernels.stiff_bed_kernels): the exact full-contact
propagator against a fine ODE solution, a free-rocking trajectory of the kernel against ``solve_ivp`` on
the numpy reference, the compiled transfer-table reader against ``np.interp``."""

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import screening
from screening.kernels import stiff_bed_contact, stiff_bed_kernels as sb
from screening.solvers.stiff_bed import StiffBedModel
from test_stiff_bed import BEDS, STATUE, _free


def test_linear_propagator_against_a_fine_ode_solution():
    m0, c0, k0, mh, dt = 1320.0, 5e3, 1.04e8, 1080.0, 4e-4
    phi, gamma = sb.linear_propagator(m0, c0, k0, mh, dt)
    u0, u1, d0, d1 = 1.3, -0.7, 2e3, -4e3
    x0 = np.array([2e-6, -3e-4])

    def u(t):
        return screening.core.interpolation.hermite(u0, u1, d0, d1, t / dt, dt)

    sol = solve_ivp(lambda t, y: [y[1], (mh * u(t) - c0 * y[1] - k0 * y[0]) / m0], (0, dt), x0, rtol=1e-12,
                    atol=1e-18, method="DOP853")
    exact = phi @ x0 + gamma @ np.array([u0, u1, dt * d0, dt * d1])
    np.testing.assert_allclose(exact, sol.y[:, -1], rtol=1e-9)


def test_kernel_free_rocking_matches_the_numpy_reference_ode():
    """Uplift phase from rest at 0.2 rad to just before the first transfer: the compiled model against
    solve_ivp on :func:`~screening.kernels.stiff_bed_contact.rocking_acceleration`."""
    bed = BEDS[0]
    t, theta, _ = _free(StiffBedModel(transfer="none"), STATUE, bed, 0.2, 0.4, output_dt=0.01)
    sol = solve_ivp(lambda s, y: [y[1], float(stiff_bed_contact.rocking_acceleration(y[0], y[1], 0.0, STATUE, bed))], (0, 0.4),
                    [0.2, 0.0], t_eval=t, rtol=1e-11, atol=1e-13, method="DOP853")
    assert np.all(theta > 0.0)
    np.testing.assert_allclose(theta, sol.y[0], rtol=0, atol=2e-6 * 0.2)


def test_compiled_transfer_ratio_is_the_log_linear_interpolant_of_the_table():
    log_amp = np.log(np.array([1e-5, 3e-5, 1e-3, 0.1]))
    log_eta = np.log(np.array([1.0, 0.99, 0.95, 0.9]))
    for amp in (5e-6, 1e-5, 2e-5, 4e-4, 0.05, 0.1, 0.3):
        ref = math.exp(np.interp(math.log(amp), log_amp, log_eta))
        assert sb.transfer_ratio_jit(log_amp, log_eta, amp) == pytest.approx(ref, rel=1e-14)



def test_step_counts_by_phase_add_up_to_the_kernels_totals():
    """The kernel's own step counts by phase (``COUNT_ROWS``, asked through ``step_counts``) sum to its
    accepted plus rejected steps on a Monte Carlo run that rocks, and every phase of the statue's bed is
    visited; counting does not change the samples."""
    counted = []

    class Counting(StiffBedModel):
        def integrator(self, *args, **kwargs):
            integrate = super().integrator(*args, **kwargs)
            integrate.step_counts = np.zeros((len(sb.COUNT_ROWS), 2), dtype=np.int64)
            counted.append(integrate)
            return integrate

    bed = BEDS[0]
    kw = dict(n_samples=6, t_end=6.0, seed=4, progress=False, strict_validity=False)
    excitation = screening.KanaiTajimi(0.015, 15.6, 0.6)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")                         # the validity warning: not the subject here
        ds = screening.monte_carlo(STATUE, bed, excitation, model=Counting(), **kw)
        plain = screening.monte_carlo(STATUE, bed, excitation, model=StiffBedModel(), **kw)
    counts = counted[-1].step_counts
    assert counts[:6].sum() + counts[7, 0] == int(ds.n_steps.sum())
    assert np.all(counts[:6, 0] > 0)
    assert 0 < counts[6, 1] <= 6 * (ds.t.size - 1)              # landings on output instants
    np.testing.assert_array_equal(ds.peak_abs_theta.values, plain.peak_abs_theta.values)
