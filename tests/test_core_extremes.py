"""Property tests: at the edges of the parameter space the core gives finite numbers or a flag."""

import numpy as np
from hypothesis import HealthCheck, given, seed, settings, strategies as st

from screening.excitation import KanaiTajimi, WhiteNoise
from screening.linearization import equivalent_coefficients
from screening.lyapunov import STATUS_OK, solve_moments
from screening.model import Block, Foundation, WinklerFoundation
from screening.timegrid import output_times

log_uniform = lambda lo, hi: st.floats(np.log10(lo), np.log10(hi)).map(lambda e: 10.0**e)

blocks = st.builds(lambda m, b, slender: Block(m, b, b * slender),
                   log_uniform(0.1, 1e4), log_uniform(0.005, 2.0), log_uniform(0.2, 50.0))
foundations = st.one_of(
    st.builds(Foundation, log_uniform(1e4, 1e10), st.one_of(st.just(0.0), log_uniform(1.0, 1e11)),
              st.one_of(st.just(0.0), log_uniform(1.0, 1e9), log_uniform(1.0, 1e7).map(lambda e: -e))),
    st.builds(WinklerFoundation, log_uniform(1e4, 1e10), st.one_of(st.just(0.0), log_uniform(1e-3, 1e7))),
)
excitations = st.one_of(
    st.builds(WhiteNoise, log_uniform(1e-12, 1e2)),
    st.builds(KanaiTajimi, log_uniform(1e-12, 1e2), log_uniform(0.5, 200.0), log_uniform(0.01, 2.0)),
)


@seed(20261122)
@settings(max_examples=300, deadline=None)
@given(blocks, foundations, log_uniform(1e-8, 1e4), st.floats(-0.999, 0.999))
def test_equivalent_coefficients_are_finite_everywhere(block, foundation, ratio, rho):
    from screening.condensed import uplift_threshold
    s = np.array([0.0, ratio * uplift_threshold(block, foundation)])
    with np.errstate(over="raise", divide="raise", invalid="raise"):  # nothing may hide an inf or 0/0
        c_eq, k_eq = equivalent_coefficients(s, 30 * s, rho, block, foundation)
    assert np.all(np.isfinite(c_eq)) and np.all(np.isfinite(k_eq))
    assert np.all(c_eq >= 0)


@seed(20261122)
@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(blocks, foundations, excitations)
def test_solver_returns_finite_values_or_a_flag(block, foundation, excitation):
    t = output_times(20.0, 0.5)
    res = solve_moments(block, foundation, excitation, t, max_steps=20_000)
    status, stop = int(res["status"]), float(res["t_stop"])
    done = t <= stop
    for name in ("var_theta", "var_theta_dot", "c_eq", "k_eq", "p_uplift"):
        assert np.all(np.isfinite(res[name][done])), name
        assert np.all(np.isnan(res[name][~done])), name
    assert np.all(res["var_theta"][done] >= 0) and np.all(res["var_theta_dot"][done] >= 0)
    if status == STATUS_OK:
        assert stop == t[-1] and np.isfinite(res["peak_var_theta"])
    else:
        assert stop <= t[-1]
