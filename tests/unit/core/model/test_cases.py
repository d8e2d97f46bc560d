"""The paper's reference configurations (screening.core.model.cases)."""

import pytest

from screening.core.model.cases import PAPER_BED, PAPER_BLOCK, PAPER_CASES, paper_case


@pytest.mark.parametrize("name", sorted(PAPER_CASES))
def test_every_case_builds_the_paper_block_bed_and_excitation(name):
    eps, kind, S0, figure = PAPER_CASES[name]
    block, bed, excitation = paper_case(name)
    assert (block.m, block.b, block.h) == (PAPER_BLOCK["m"], PAPER_BLOCK["b"], PAPER_BLOCK["h"])
    assert (bed.k, bed.lam, bed.eps) == (PAPER_BED["k"], PAPER_BED["lam"], eps)
    assert excitation.kind == kind and excitation.S0 == S0 and f"fig{figure}_" in name
    if kind == "kanai_tajimi":
        assert (excitation.omega_g, excitation.zeta_g) == (10.0, 0.4)


def test_an_unknown_case_is_refused():
    with pytest.raises(KeyError):
        paper_case("fig1")
