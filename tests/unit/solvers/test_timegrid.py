"""The output time coordinate every solver shares (screening.solvers.timegrid)."""

import numpy as np
import pytest

from screening.core import limits
from screening.solvers.timegrid import output_times


def test_the_grid_runs_from_zero_to_t_end_in_whole_steps():
    t = output_times(2.0, 0.25)
    np.testing.assert_allclose(t, np.arange(9) * 0.25, rtol=0, atol=0)
    assert t[-1] == 2.0 and output_times(0.1, 0.1).tolist() == [0.0, 0.1]


@pytest.mark.parametrize("t_end, dt, parameter", [(2.0, 0.3, "dt"), (-1.0, 0.1, "t_end"), (1.0, 2.0, "dt"),
                                                   (1.0, 0.0, "dt"), (float("nan"), 0.1, "t_end")])
def test_a_bad_grid_is_one_line_naming_the_parameter(t_end, dt, parameter):
    with pytest.raises(ValueError, match=f"^parameter '{parameter}'"):
        output_times(t_end, dt)


def test_too_many_steps_are_refused_before_any_array_is_built():
    with pytest.raises(ValueError, match=f"at most {limits.MAX_TIMES - 1}"):
        output_times(1.0, 0.5 / limits.MAX_TIMES)
