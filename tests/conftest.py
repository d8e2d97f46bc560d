import pytest

from screening.core.model.cases import PAPER_BED, PAPER_BLOCK
from screening.core.model import Block, Foundation
from screening.core.excitations.white import WhiteNoise


@pytest.fixture
def paper_block():
    return Block(**PAPER_BLOCK)


@pytest.fixture(params=["hc_hardening", "hc_softening", "hc_strong_softening", "winkler_cubic"])
def any_foundation(request):
    return {
        "hc_hardening": Foundation(eps=6e7, **PAPER_BED),
        "hc_softening": Foundation(eps=-6e5, **PAPER_BED),
        "hc_strong_softening": Foundation(eps=-3e8, **PAPER_BED),
        "winkler_cubic": Foundation(k=2.89e7, c=2.0e3, eps=1e7),
    }[request.param]


#: Beds for the "cubic" condensation: both signs of eps, both damping laws, and a softening
#: bed whose capacity angle (3.5 theta_ul) is within reach.  (hc_strong_softening above cannot
#: carry the paper's block through uplift under "cubic": it is tested to raise.)
CUBIC_BEDS = {
    "hc_hardening": Foundation(k=2.89e7, lam=8.95e8, eps=6e7),
    "hc_softening": Foundation(k=2.89e7, lam=8.95e8, eps=-6e5),
    "hc_capacity": Foundation(k=2.89e7, lam=8.95e8, eps=-2e7),
    "winkler_hardening": Foundation(k=2.89e7, c=2.0e3, eps=1e7),
    "winkler_softening": Foundation(k=2.89e7, c=2.0e3, eps=-2e7),
}


@pytest.fixture(params=list(CUBIC_BEDS))
def cubic_bed(request):
    return CUBIC_BEDS[request.param]


@pytest.fixture(scope="module")
def client():
    """A 2-worker in-process dask client, one per test module."""
    from helpers import in_process_client

    with in_process_client(2) as c:
        yield c


@pytest.fixture(scope="module")
def one_worker():
    """A 1-worker in-process dask client, one per test module."""
    from helpers import in_process_client

    with in_process_client(1) as c:
        yield c


def pytest_sessionstart(session):
    """On a cold numba cache (a fresh clone), compile the solvers once before the first test, saying so:
    otherwise the first test that solves a point is silent for the whole compilation (about a minute)."""
    from screening.kernels.cache import cache_is_cold

    if not cache_is_cold():
        return
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
        reporter.write_line("screening: compiling the solvers with numba before the tests (first run only, "
                            "about a minute)...")
    import time

    import numpy as np

    from screening.analysis.linearization import linearize
    from screening.sweep._submit import warm_up_monte_carlo
    from screening.sweep.execution import warm_up

    start = time.perf_counter()
    warm_up()
    warm_up_monte_carlo()
    for condensation in ("cubic", "paper"):          # warm_up solves with the default (virtual_work); these two
        linearize(Block(**PAPER_BLOCK), Foundation(eps=6e7, **PAPER_BED), WhiteNoise(1e-5), t_end=0.1, dt=0.1,
                  condensation=condensation, trust=False)   # have solver kernels of their own
    seconds = time.perf_counter() - start
    if reporter is not None:
        reporter.write_line(f"screening: compiled in {seconds:.0f} s")
