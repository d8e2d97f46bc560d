"""Bed parameters from materials: the helpers reproduce the model's own quantities."""

import math

import numpy as np
import pytest

import screening
from screening.analysis import beds
from screening.core.model import Block, Foundation
from screening.report.text import bed_lines

BLOCK = Block(m=8.67, b=0.035, h=0.21)


def test_layer_stiffness_and_moduli():
    assert beds.layer_stiffness(2e6, 0.01, 0.1) == pytest.approx(2e7)
    assert beds.oedometric_modulus(1.0, 0.0) == 1.0
    assert beds.oedometric_modulus(1.0, 0.25) == pytest.approx(0.75 / (1.25 * 0.5))
    with pytest.raises(ValueError, match="nu"):
        beds.oedometric_modulus(1.0, 0.5)
    ec = beds.pad_compression_modulus(3e6, 5.0, kappa=0.75, bulk_modulus=np.inf)
    assert ec == pytest.approx(3e6 * (1 + 2 * 0.75 * 25))


def test_vertical_damping_helpers_give_the_ratio_back():
    k, zeta = 2.89e7, 0.1
    c = beds.c_from_vertical_damping(k, BLOCK.m, BLOCK.b, zeta)
    s = beds.bed_summary(BLOCK, Foundation(k=k, c=c))
    assert s["vertical_damping_ratio"] == pytest.approx(zeta, rel=1e-12)
    lam = beds.lam_from_vertical_damping(k, BLOCK.m, BLOCK.b, zeta)
    s = beds.bed_summary(BLOCK, Foundation(k=k, lam=lam))
    assert s["vertical_damping_ratio"] == pytest.approx(zeta, rel=1e-12)


def test_restitution_formulas():
    """Linear spring-dashpot restitution and the three Hunt-Crossley-type lam(e, v) models as documented."""
    zeta = 0.2
    e = float(beds.restitution_from_damping_ratio(zeta))
    assert e == pytest.approx(math.exp(-math.pi * 0.2 / math.sqrt(0.96)))
    alpha = beds.hunt_crossley_lambda(1.0, 0.8, 0.5)
    assert alpha == pytest.approx(1.5 * 0.2 / 0.5)
    assert beds.hunt_crossley_lambda(1.0, 0.8, 0.5, "flores") == pytest.approx(1.6 * 0.2 / (0.8 * 0.5))
    with pytest.raises(ValueError, match="restitution"):
        beds.hunt_crossley_lambda(1.0, 0.0, 1.0)


def test_backbone_fit_recovers_k_and_eps():
    z = np.linspace(1e-5, 2e-4, 20)
    f = 2.89e7 * z * (1 + 6e7 * z * z)
    k, eps = beds.fit_backbone(z, f)
    assert k == pytest.approx(2.89e7, rel=1e-9) and eps == pytest.approx(6e7, rel=1e-6)
    assert beds.fit_backbone(z, f, k=2.89e7)[1] == pytest.approx(6e7, rel=1e-9)


def test_summary_matches_the_model():
    bed = Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
    s = beds.bed_summary(BLOCK, bed)
    assert s["uplift_angle"] == pytest.approx(float(screening.uplift_threshold(BLOCK, bed, condensation="paper")))
    assert s["slenderness"] == pytest.approx(math.atan(0.035 / 0.21))
    assert s["vertical_frequency"] == pytest.approx(math.sqrt(2 * 0.035 * 2.89e7 / 8.67))
    f_static = 2 * BLOCK.b * bed.k * s["static_indentation"] * (1 + bed.eps * s["static_indentation"] ** 2)
    assert f_static == pytest.approx(BLOCK.m * BLOCK.g, rel=1e-12)


def test_info_prints_the_bed():
    ds = screening.linearize(BLOCK, Foundation(k=2.89e7, lam=8.95e8), screening.WhiteNoise(1e-4), t_end=1.0, dt=0.1)
    text = "\n".join(bed_lines(ds))
    for word in ("static indentation", "uplift angle", "slenderness", "rocking frequency", "vertical frequency",
                 "vertical"):
        assert word in text


def test_format_bed_summary_returns_text():
    """Issue 36 item 12: the name promises text; it returned a list."""
    from screening import Block, Foundation
    from screening.analysis.beds import bed_summary, format_bed_summary

    text = format_bed_summary(bed_summary(Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8)))
    assert isinstance(text, str) and text.splitlines()[1].startswith("uplift angle")
