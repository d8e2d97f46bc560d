import pytest

from screening.cases import PAPER_BED, PAPER_BLOCK
from screening.model import Block, Foundation, WinklerFoundation


@pytest.fixture
def paper_block():
    return Block(**PAPER_BLOCK)


@pytest.fixture(params=["hc_hardening", "hc_softening", "hc_strong_softening", "winkler_cubic"])
def any_foundation(request):
    return {
        "hc_hardening": Foundation(eps=6e7, **PAPER_BED),
        "hc_softening": Foundation(eps=-6e5, **PAPER_BED),
        "hc_strong_softening": Foundation(eps=-3e8, **PAPER_BED),
        "winkler_cubic": WinklerFoundation(k=2.89e7, c=2.0e3, eps=1e7),
    }[request.param]
