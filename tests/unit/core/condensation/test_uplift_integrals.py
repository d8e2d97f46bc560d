"""The tabulated coefficients used by the compiled solver against the closed forms."""

from functools import partial

import numpy as np
import pytest

from screening.core.condensation import api
from screening.core.condensation.uplift_integrals import R_HI, R_LO, coefficient_table, uplift_integrals
from screening.core.condensation.uplift_integrals import gaussian_uplift_integrals
from screening.core.condensation.paper import equivalent_coefficients_jit, records

#: the paper's condensation, pinned (the compiled coefficients are the paper's; the default is another)
equivalent_coefficients_from_moments = partial(api.equivalent_coefficients_from_moments, condensation="paper")


def test_table_matches_closed_forms_across_and_beyond_the_grid():
    table = coefficient_table()
    r = np.exp(np.concatenate([np.linspace(np.log(R_LO) - 2, np.log(R_HI) + 3, 20011), [-np.inf]]))
    G = gaussian_uplift_integrals(r)
    inner_over_r2 = np.where(r > 0, G["inner_m2"] / np.where(r > 0, r, 1) ** 2, 1.0)
    for i, ri in enumerate(r):
        got = uplift_integrals(ri, table)
        ref = (G["p_in"][i], G["tail_m12"][i], G["tail_m32"][i], inner_over_r2[i])
        # absolute error against O(1) terms of c_eq, k_eq
        np.testing.assert_allclose(got, ref, rtol=1e-10, atol=2e-12)


@pytest.mark.parametrize("rho_sign", [-1.0, 0.0, 1.0])
def test_compiled_coefficients_match_closed_forms(paper_block, any_foundation, rho_sign):
    table = coefficient_table()
    p = records(paper_block, any_foundation)[0]
    tu = p["theta_ul"]
    for ratio in np.concatenate([[0.0], np.logspace(-3, 5, 97)]):
        s = ratio * tu
        var, cov = s * s, rho_sign * 0.9 * s * (40 * s)
        c_ref, k_ref = equivalent_coefficients_from_moments(var, cov, paper_block, any_foundation)
        c, k = equivalent_coefficients_jit(p, table, var, cov)
        scale_k = abs(2 / 3 * 0.035**3 * any_foundation.k)
        assert c == pytest.approx(c_ref, rel=1e-9, abs=1e-12 * c_ref)
        assert k == pytest.approx(k_ref, rel=1e-9, abs=1e-11 * scale_k)
