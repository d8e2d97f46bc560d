"""screening.simulate against independent solutions: closed-form free rocking, a fine-step
reference for a pulse, the sign convention and the mirror symmetry."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import screening
from screening.core.model import Block, Foundation
from screening.core.physics.contact import contact_resultants
from screening.core.records import Record

BLOCK = Block(m=100.0, b=0.2, h=0.6)
HC_BED = Foundation(k=5e7, lam=2e8)


def _winkler_for_damping(zeta):
    """A linear Winkler bed giving the rocking damping ratio ``zeta`` in full contact."""
    k = 5e7
    stiffness = 2.0 / 3.0 * BLOCK.b**3 * k - BLOCK.m * BLOCK.g * BLOCK.h
    c = 2.0 * zeta * math.sqrt(stiffness * BLOCK.m_sdof) / (2.0 / 3.0 * BLOCK.b**3)
    return Foundation(k=k, c=c), stiffness


@pytest.mark.parametrize("model", ["coupled", "condensed"])
def test_free_rocking_matches_closed_form(model):
    """Linear bed, full contact (theta0 = 0.1 theta_ul): theta(t) = theta0 e^{-zeta w t}(cos w_d t + ...)
    with w^2 = ((2/3) b^3 k - m g h) / (I_cm + m h^2), zeta = (2/3) c b^3 / (2 sqrt(K m_sdof))."""
    zeta = 0.05
    bed, stiffness = _winkler_for_damping(zeta)
    theta_ul = BLOCK.m * BLOCK.g / (2 * BLOCK.b**2 * bed.k)
    theta0 = 0.1 * theta_ul
    ds = screening.simulate(BLOCK, bed, np.zeros(3), dt=0.001, t_end=1.0, theta0=theta0, model=model)
    assert ds.attrs["status"] == "ok"
    assert np.all(ds.contact_regime.values == 0)
    w = math.sqrt(stiffness / BLOCK.m_sdof)
    wd = w * math.sqrt(1 - zeta**2)
    t = ds.t.values
    exact = theta0 * np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t))
    err = np.max(np.abs(ds.theta.values - exact)) / theta0
    # measured: 4.5e-9 (coupled, rtol 1e-7), 4.4e-9 (condensed, rtol 1e-6)
    assert err < 1e-4


def test_sign_convention_and_mirror():
    """A positive ground-acceleration pulse (ground towards +x) first tips the block towards -x
    (theta < 0); the mirrored record gives the mirrored response with the same z_cb."""
    dt = 0.002
    t = np.arange(0.0, 1.5, dt)
    a = np.where(t < 0.3, 2.0 * np.sin(np.pi * t / 0.3), 0.0)
    ds = screening.simulate(BLOCK, HC_BED, a, dt=dt)
    mirror = screening.simulate(BLOCK, HC_BED, -a, dt=dt)
    first = np.flatnonzero(np.abs(ds.theta.values) > 1e-3 * float(ds.peak_abs_theta))[0]
    assert ds.theta.values[first] < 0.0
    np.testing.assert_allclose(mirror.theta.values, -ds.theta.values, rtol=0, atol=1e-12 * float(ds.peak_abs_theta))
    np.testing.assert_allclose(mirror.z_cb.values, ds.z_cb.values, rtol=1e-12)
    regimes = ds.contact_regime.values
    assert set(np.unique(regimes)) >= {0, 2}         # uplift with theta < 0 happens
    np.testing.assert_array_equal(np.where(regimes == 1, 2, np.where(regimes == 2, 1, regimes)),
                                  mirror.contact_regime.values)


def _reference(block, bed, accel, t_end, t_eval):
    """Eqs. (7)-(8) as printed, solved for (theta'', z_cb'') by a 2x2 linear solve each call, with the
    numpy contact resultants and scipy's DOP853 at rtol 1e-11 (an independent integrator)."""
    m, g, h, b, I_cm = block.m, block.g, block.h, block.b, block.I_cm
    M = I_cm + m * h * h

    def rhs(t, y):
        th, thd, z, zd = y
        F, Mcb = contact_resultants(th, thd, z, zd, b, bed.k, bed.eps, bed.damping, bed.winkler)
        s, c = math.sin(th), math.cos(th)
        xg = -accel(t)                                   # the kernel's input: -ground acceleration
        # (7): m z'' + m h s th'' = m g - F - m h thd^2 c ;  (8): M th'' + m h s z'' = m h xg c - Mcb + m h g s
        A = np.array([[m, m * h * s], [m * h * s, M]])
        rhs_ = np.array([m * g - float(F) - m * h * thd * thd * c, m * h * xg * c - float(Mcb) + m * h * g * s])
        zdd, thdd = np.linalg.solve(A, rhs_)
        return [thd, thdd, zd, zdd]

    z0 = block.m * block.g / (2 * block.b * bed.k)
    sol = solve_ivp(rhs, (0.0, t_end), [0.0, 0.0, z0, 0.0], method="DOP853", rtol=1e-11, atol=[1e-13, 1e-11, 1e-15, 1e-13],
                    t_eval=t_eval, max_step=0.002)
    assert sol.success
    return sol.y


def test_pulse_against_fine_step_reference():
    """One-sine pulse through uplift: simulate vs an independent DOP853 reference of eqs. (7)-(8)."""
    amplitude, tp, dt, t_end = 3.0, 0.4, 0.0005, 1.0
    accel = lambda t: amplitude * math.sin(math.pi * t / tp) if t < tp else 0.0   # noqa: E731
    t = np.arange(0.0, t_end + dt / 2, dt)
    record = Record(np.array([accel(x) for x in t]), dt, name="pulse")
    ds = screening.simulate(BLOCK, HC_BED, record, rtol=1e-9, output_dt=0.01)
    ref = _reference(BLOCK, HC_BED, accel, t_end, ds.t.values)
    peak = float(np.max(np.abs(ref[0])))
    theta_ul = BLOCK.m * BLOCK.g / (2 * BLOCK.b**2 * HC_BED.k)
    assert peak > 5 * theta_ul                           # well into uplift
    err = np.max(np.abs(ds.theta.values - ref[0])) / peak
    # measured 1.4e-5 (theta) and 1.5e-5 (z_cb): the record's Hermite interpolation (finite-difference
    # slopes, kink at the pulse end); peak 40 theta_ul
    assert err < 1e-3
    np.testing.assert_allclose(ds.z_cb.values, ref[2], rtol=0, atol=1e-3 * float(np.max(np.abs(ref[2]))))


def test_overturning_time_and_nan_after():
    dt = 0.005
    t = np.arange(0.0, 6.0, dt)
    a = 15.0 * np.sin(2 * np.pi * 1.5 * t) * np.exp(-((t - 3) / 1.5) ** 2)
    ds = screening.simulate(BLOCK, HC_BED, a, dt=dt)
    assert bool(ds.overturned) and ds.attrs["status"] == "overturned"
    t_over = float(ds.overturning_time)
    last = ds.t.values[np.isfinite(ds.theta.values)][-1]
    assert last < t_over <= last + dt
    assert np.all(ds.contact_regime.values[ds.t.values > t_over] == -1)


def test_initial_conditions_and_errors():
    ds = screening.simulate(BLOCK, HC_BED, np.zeros(10), dt=0.01, theta0=0.01, theta_dot0=0.1)
    assert float(ds.theta[0]) == 0.01 and float(ds.theta_dot[0]) == 0.1
    # z_cb0 carries the weight at theta0 (quasi-static)
    F, _ = contact_resultants(0.01, 0.0, float(ds.z_cb[0]), 0.0, BLOCK.b, HC_BED.k, 0.0, HC_BED.lam, False)
    assert float(F) == pytest.approx(BLOCK.m * BLOCK.g, rel=1e-9)
    with pytest.raises(ValueError, match="theta0"):
        screening.simulate(BLOCK, HC_BED, np.zeros(10), dt=0.01, theta0=0.4)
    with pytest.raises(ValueError, match="dt"):
        screening.simulate(BLOCK, HC_BED, np.zeros(10))
    with pytest.raises(ValueError, match="model"):
        screening.simulate(BLOCK, HC_BED, np.zeros(10), dt=0.01, model="x")
