"""The intensity at which the linearization reaches a target peak uplift probability
(screening.analysis.target_intensity)."""

import pytest

from screening.analysis.target_intensity import calibrate_intensity, round_significant
from screening.core.model import Block, Foundation
from screening.core.model.excitation import Envelope
from screening.core.excitations.white import WhiteNoise
from screening.solvers.moments import solve_moments
from screening.solvers.timegrid import output_times


def test_calibration_hits_the_target_uplift_probability():
    """The calibrated S0, solved again independently, gives the target peak uplift probability (the
    bisection's own check allows 10 %; the 3-digit rounding of S0 moves it by far less than 2 %)."""
    block = Block(m=8.67, b=0.035, h=0.21)
    bed = Foundation(k=2.89e7, lam=8.95e8, eps=-6e5)
    t = output_times(4.0, 0.05)
    S0 = calibrate_intensity(block, bed, lambda s: WhiteNoise(s, Envelope(4.0, 2.0)), 0.05, t)
    p = float(solve_moments(block, bed, WhiteNoise(S0, Envelope(4.0, 2.0)), t)["peak_p_uplift"])
    assert p == pytest.approx(0.05, rel=0.02)
    assert S0 == round_significant(S0, 3)
    with pytest.raises(ValueError, match="not"):
        calibrate_intensity(block, bed, lambda s: WhiteNoise(s, Envelope(4.0, 2.0)), 0.05, t,
                            log10_bounds=(-10.0, -8.0))
