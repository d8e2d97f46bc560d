"""The compiled kernels' tests take their cases from the solvers' tests (``test_montecarlo``, ``test_stiff_bed``
in tests/unit/solvers/, which these tests sat beside before the kernels had a folder of their own)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "solvers"))
