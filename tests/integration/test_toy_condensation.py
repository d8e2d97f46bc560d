"""A condensation registered from outside the package runs through the linearization and the
condensed Monte Carlo without any change to them (the plug-in interface of screening.core.condensation).

The toy is the linear oscillator of the block at rest (no uplift): ``C = C(0)``, ``K = K(0)`` of
the paper's condensation for every theta.  Under stationary white noise its rotation variance is
``pi S0 a^2 / (2 zeta w^3)`` (``a = m h / m_sdof``), and under the synthesised band-limited input
the same integral cut at the synthesis band limit.
"""

import numba
import numpy as np
import pytest
from scipy import integrate

from screening.core import condensation
from screening.core.condensation.base import SdofKernel
from screening.core.signatures import sdof_coefficients_signature
from screening.core.model import Block, ConstantEnvelope, Foundation
from screening.core.excitations import WhiteNoise
from screening.solvers.moments import solve_moments
from screening.solvers.montecarlo import monte_carlo
from screening.solvers.synthesis import default_cutoff
from screening.solvers.timegrid import output_times

BLOCK = Block(m=8.67, b=0.035, h=0.21)
BED = Foundation(k=2.89e7, lam=8.95e8, eps=0.0)
S0 = 1e-7                 # far below uplift: the paper's and the toy's responses then agree too

TOY_RECORD = np.dtype([("c", "f8"), ("k", "f8")])


@numba.njit(sdof_coefficients_signature(TOY_RECORD), cache=True)
def toy_damping_stiffness(p, theta):
    return p.c, p.k


class LinearToy(condensation.Condensation):
    """No uplift at all: the block rocks as the linear oscillator it is at rest."""

    name = "linear_toy"
    description = "test: C(theta) = C(0), K(theta) = K(0) of the paper's condensation"

    def __init__(self):
        self.paper = condensation.get("paper")

    def uplift_threshold(self, block, foundation):
        return self.paper.uplift_threshold(block, foundation)     # sets the table scale only

    def rocking_damping(self, theta, block, foundation):
        return self.paper.damping_at_rest(block, foundation) + 0.0 * np.asarray(theta, dtype=float)

    def rocking_stiffness(self, theta, block, foundation):
        return self.paper.stiffness_at_rest(block, foundation) + 0.0 * np.asarray(theta, dtype=float)

    def sdof_kernel(self, block, foundation):
        rec = np.zeros(1, dtype=TOY_RECORD)
        rec["c"] = self.paper.damping_at_rest(block, foundation)
        rec["k"] = self.paper.stiffness_at_rest(block, foundation)
        return SdofKernel(toy_damping_stiffness, rec)


@pytest.fixture(scope="module")
def toy():
    cond = condensation.register(LinearToy())
    yield cond
    condensation.unregister(cond.name)


def linear_constants():
    m_sdof = BLOCK.m_sdof
    c0 = condensation.get("paper").damping_at_rest(BLOCK, BED)
    k0 = condensation.get("paper").stiffness_at_rest(BLOCK, BED)
    w = np.sqrt(k0 / m_sdof)
    zeta = c0 / (2.0 * m_sdof * w)
    return w, zeta, BLOCK.m * BLOCK.h / m_sdof


def test_toy_is_registered_by_name_and_refused_once_removed(toy):
    assert condensation.get("linear_toy") is toy and "linear_toy" in condensation.names()
    condensation.unregister("linear_toy")
    with pytest.raises(ValueError, match="'condensation'"):
        condensation.get("linear_toy")
    condensation.register(toy)


def test_linearization_with_the_toy_gives_the_linear_stationary_variance(toy):
    w, zeta, a = linear_constants()
    expected = np.pi * S0 * a**2 / (2.0 * zeta * w**3)
    t = output_times(12.0, 0.5)
    for cond in ("linear_toy", toy):                       # by name (registry) and by object
        res = solve_moments(BLOCK, BED, WhiteNoise(S0, ConstantEnvelope()), t, condensation=cond)
        assert int(res["status"]) == 0
        assert res["var_theta"][-1] == pytest.approx(expected, rel=1e-3)
        np.testing.assert_allclose(res["c_eq"], 2.0 * zeta * w * BLOCK.m_sdof, rtol=1e-9)
        np.testing.assert_allclose(res["k_eq"], w**2 * BLOCK.m_sdof, rtol=1e-9)


def test_toy_and_paper_agree_where_the_paper_block_does_not_uplift(toy):
    t = output_times(12.0, 0.5)
    exc = WhiteNoise(S0, ConstantEnvelope())
    paper = solve_moments(BLOCK, BED, exc, t)
    lin = solve_moments(BLOCK, BED, exc, t, condensation=toy)
    assert float(paper["peak_p_uplift"]) < 1e-12
    np.testing.assert_allclose(lin["var_theta"], paper["var_theta"], rtol=1e-4, atol=1e-6 * paper["var_theta"].max())


@pytest.mark.slow
def test_condensed_monte_carlo_with_the_toy_matches_the_band_limited_linear_variance(toy):
    w, zeta, a = linear_constants()
    cutoff = default_cutoff(BLOCK, BED)
    h2 = lambda om: a**2 / ((w**2 - om**2) ** 2 + (2.0 * zeta * w * om) ** 2)
    expected = 2.0 * S0 * integrate.quad(h2, 0.0, cutoff, points=[w], limit=400, epsrel=1e-10)[0]
    assert expected == pytest.approx(np.pi * S0 * a**2 / (2.0 * zeta * w**3), rel=0.01)   # the band holds it
    ds = monte_carlo(BLOCK, BED, WhiteNoise(S0, ConstantEnvelope(), band_limit_hz=None), n_samples=1000, model="condensed",
                     t_end=12.0, dt=0.5, seed=7, condensation=toy)
    assert int(ds.n_used) == 1000
    late = ds.t.values >= 6.0                                 # ~6 decay times of the linear oscillator
    var = float(ds.var_theta.values[late].mean())
    se = float(ds.var_theta_se.values[late].mean())           # per-time SE: the time average's is smaller
    assert abs(var - expected) < 3.0 * se, (var, expected, se)
    assert se < 0.06 * expected                               # the check can fail: 3 SE is < 18 %
