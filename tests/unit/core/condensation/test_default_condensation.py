"""The default condensation is stated once (``screening.core.condensation.DEFAULT_CONDENSATION``) and every
entry point that takes a condensation reads it; the paper reproduction pins ``"paper"``."""

import inspect
from pathlib import Path

import numpy as np
import pytest
from helpers import study_text

from screening import Block, Foundation
from screening.core import condensation as condensations
from screening.core.condensation import DEFAULT_CONDENSATION, api
from screening.solvers.datasets import monte_carlo_dataset
from screening.analysis.linearization import linearize
from screening.kernels.moment_kernels import moment_equations
from screening.solvers.moments import solve_moments
from screening.solvers.montecarlo import monte_carlo
from screening.solvers.simulate import simulate
from screening.sweep import config
from screening.sweep.study import load_study, parse_study

ROOT = Path(__file__).resolve().parents[4]

#: one point of the paper's block on a linear bed, no condensation chosen
STUDY = study_text({"eps": "0.0", "S0": "1e-4", "t_end": "2.0"})


def test_the_default_is_a_registered_condensation():
    assert condensations.get(DEFAULT_CONDENSATION).name == DEFAULT_CONDENSATION


@pytest.mark.parametrize("function", [linearize, solve_moments, moment_equations, monte_carlo, simulate,
                                      monte_carlo_dataset, *(getattr(api, name) for name in api.__all__)],
                         ids=lambda f: f.__name__)
def test_every_entry_point_defaults_to_the_one_constant(function):
    assert inspect.signature(function).parameters["condensation"].default == DEFAULT_CONDENSATION


def test_a_study_without_condensation_uses_the_default_and_paper_cases_pin_the_paper():
    assert config.DEFAULTS["condensation"] == DEFAULT_CONDENSATION
    assert config.Case("c", "hunt_crossley", "white", "exponential", {}).condensation == DEFAULT_CONDENSATION
    assert {case.condensation for case in parse_study(STUDY).cases} == {DEFAULT_CONDENSATION}
    assert {case.condensation for case in load_study(ROOT / "studies" / "paper_cases.toml").cases} == {"paper"}


def test_the_default_functions_are_those_of_the_virtual_work_condensation():
    """Beyond uplift the default's damping is the virtual-work one, ``C1 theta_ul / |theta|`` on a
    linear Hunt-Crossley bed (``virtual_work`` module docstring), not the paper's
    ``C1 (theta_ul / |theta|)^(1/2)`` (eq. 24): both computed here from ``C1`` and ``theta_ul``."""
    block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8)
    c1 = bed.lam * block.b ** 2 * block.m * block.g / (3.0 * bed.k)
    theta_ul = block.m * block.g / (2.0 * block.b ** 2 * bed.k)
    theta = np.array([0.5, 4.0, 30.0]) * theta_ul
    expected = c1 * np.minimum(1.0, theta_ul / theta)
    np.testing.assert_allclose(api.rocking_damping(theta, block, bed), expected, rtol=1e-9)
    paper = c1 * np.minimum(1.0, np.sqrt(theta_ul / theta))
    np.testing.assert_allclose(api.rocking_damping(theta, block, bed, condensation="paper"), paper, rtol=1e-9)


def test_the_coupled_model_takes_the_default_or_the_paper_and_refuses_another_condensation():
    """The coupled model is not condensed: the default and the paper's (what its kernel is built with,
    and what callers pass for "none") pass, another is refused by name before any sample."""
    from screening.solvers.mc_registry import get

    block, bed = Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8)
    get("coupled").check(block, bed, DEFAULT_CONDENSATION)
    get("coupled").check(block, bed, "paper")
    with pytest.raises(ValueError, match="parameter 'condensation' applies to model='condensed' only"):
        get("coupled").check(block, bed, "cubic")


def test_a_bed_the_default_cannot_condense_is_refused_with_a_pointer_to_paper():
    """A softening bed beyond the bearing limit (``|eps| z^2 >= 2/27``) under the default: one line that
    names the parameter and the condensation that carries every bed."""
    text = STUDY.replace("eps = 0.0", "eps = -2e8")
    with pytest.raises(config.StudyError) as info:
        parse_study(text)
    message = str(info.value)
    assert "'virtual_work' needs a bed it can condense" in message and "parameter 'foundation.eps'" in message
    assert message.endswith("; use condensation = 'paper'") and "\n" not in message
    parse_study(text.replace("[foundation]", '[foundation]\ncondensation = "paper"'))
