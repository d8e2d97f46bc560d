"""The "virtual_work" condensation against the coupled model, deterministically: free rocking of the
paper's block released in uplift loses per half cycle what the coupled block loses (the paper's
condensation loses up to twice as much; docs/heavy_uplift.md), and the condensation runs through the
linearization and the condensed Monte Carlo by name.
"""

import numpy as np
import pytest

from screening.core.model import Block, Foundation
from screening.core.excitations import WhiteNoise
from screening.analysis.linearization import linearize
from screening.solvers.montecarlo import monte_carlo
from screening.solvers.simulate import simulate

BLOCK = Block(m=8.67, b=0.035, h=0.21)
BED = Foundation(k=2.89e7, lam=8.95e8, eps=0.0)
THETA_UL = BLOCK.m * BLOCK.g / (2 * BLOCK.b**2 * BED.k)


def half_cycle_ratio(model, condensation, ratio):
    """Mean ratio of successive rocking amplitudes over the first three half cycles [1]."""
    ds = simulate(BLOCK, BED, np.zeros(4), dt=0.1, model=model, condensation=condensation,
                  theta0=ratio * THETA_UL, t_end=1.5, output_dt=2e-5)
    th = ds.theta.values
    turn = np.flatnonzero((th[1:-1] - th[:-2]) * (th[2:] - th[1:-1]) < 0) + 1
    amp = np.abs(th[turn])
    assert amp.size >= 4
    return float(np.mean(amp[1:4] / amp[:3]))


@pytest.mark.parametrize("ratio", [10.0, 30.0])
def test_free_rocking_loses_what_the_coupled_model_loses(ratio):
    coupled = half_cycle_ratio("coupled", "paper", ratio)
    assert abs(half_cycle_ratio("condensed", "virtual_work", ratio) - coupled) < 0.005
    assert coupled - half_cycle_ratio("condensed", "paper", ratio) > 0.02


def test_runs_by_name_through_linearization_and_condensed_monte_carlo():
    exc = WhiteNoise(S0=1e-4)
    ds = linearize(BLOCK, BED, exc, condensation="virtual_work")
    paper = linearize(BLOCK, BED, exc, condensation="paper")
    assert int(ds.status) == 0 and ds.attrs["condensation"] == "virtual_work"
    # less damping in uplift: more rocking than the paper's condensation predicts
    assert float(ds.peak_var_theta) > float(paper.peak_var_theta)
    mc = monte_carlo(BLOCK, BED, exc, n_samples=4, model="condensed", condensation="virtual_work", t_end=2.0,
                     progress=False)
    assert mc.attrs["condensation"] == "virtual_work" and int(mc.n_used) == 4


def test_the_default_and_selectable_in_a_study_beside_the_paper():
    from screening.sweep.study import parse_study
    from tests.helpers import GRID

    default = parse_study(GRID, name="grid")
    chosen = parse_study(GRID.replace("eps = [-6e5, 0.0, 3e7, 6e7]",
                                      'eps = [-6e5, 0.0, 3e7, 6e7]\ncondensation = "paper"'), name="grid")
    assert [c.condensation for c in default.cases] == ["virtual_work"]
    assert [c.condensation for c in chosen.cases] == ["paper"]
