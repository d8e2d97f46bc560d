"""screening: stochastic screening of rigid blocks rocking on flexible nonlinear foundations."""

__version__ = "0.1.0"

import multiprocessing as _mp
import os as _os
import signal as _signal

#: Set to "1" by the client for the worker processes of its local cluster.
LOCAL_WORKER_VARIABLE = "SCREENING_LOCAL_WORKER"


def quiet_local_worker(_=None):
    """In a worker process of the local cluster of `screening run`: ignore SIGINT; whether it is one.

    The client sets :data:`LOCAL_WORKER_VARIABLE` to ``1`` for its workers
    (:func:`screening.workflow.execution.dask_client`).  The terminal's Ctrl-C reaches the whole
    process group, and the client stops the run with one line and closes its workers itself, so a
    worker ignores SIGINT instead of printing a traceback while it imports or computes.
    A spawned worker runs this when it imports screening, a forked one after the fork.
    """
    if (_mp.current_process().name.startswith("Dask Worker")
            and _os.environ.get(LOCAL_WORKER_VARIABLE) == "1"):
        _signal.signal(_signal.SIGINT, _signal.SIG_IGN)
        return True
    return False


if quiet_local_worker():
    # A spawned worker, when it exits (the worker closed, its work directory removed, its streams
    # flushed by multiprocessing), skips tearing down its modules: scipy, numba and xarray take
    # ~0.5 s, which the client would wait for at the end of every run.  A forked one
    # exits through os._exit already.
    import atexit as _atexit

    _atexit.register(_os._exit, 0)

from screening.analysis import fragility as fragility  # noqa: F401 - registers the ``ds.rocking`` accessor
from screening.model.excitation import ConstantEnvelope, Envelope, KanaiTajimi, WhiteNoise
from screening.condensation.api import (equivalent_coefficients, rocking_damping, rocking_stiffness,
                                        uplift_probability, uplift_threshold)
from screening.model import Block, Foundation
from screening.solvers.linearization import linearize
from screening.solvers.montecarlo import monte_carlo
from screening.solvers.simulate import simulate

__all__ = [
    "Block", "Foundation", "Envelope", "ConstantEnvelope", "WhiteNoise",
    "KanaiTajimi", "uplift_threshold", "rocking_damping", "rocking_stiffness",
    "equivalent_coefficients", "uplift_probability", "linearize", "monte_carlo", "simulate", "__version__",
]
