"""The paper's reference configurations (section 3), as model objects.

Block: m = 8.67 kg, b = 0.035 m, h = 0.21 m; bed k = 2.89e7 N/m^2, lam = 8.95e8 N s/m^3;
envelope T1 = 4 s, T2 = 2 s; records of 20 s.  The eps values are those of the figure
captions (the text of section 3 gives 2e7 / -2e5 for configurations 3 and 4: docs/method.md#values-of-eps-in-section-3).
"""

from __future__ import annotations

from screening.core.model.excitation import Envelope
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.core.model import Block, Foundation

__all__ = []

PAPER_BLOCK = dict(m=8.67, b=0.035, h=0.21)
PAPER_BED = dict(k=2.89e7, lam=8.95e8)

#: name -> (eps [1/m^2], excitation kind, S0 [m^2/s^3], figure of the paper)
PAPER_CASES = {
    "fig2_white_hardening_low": (6e7, "white", 2.4e-5, 2),
    "fig3_white_hardening_high": (6e7, "white", 2.4e-3, 3),
    "fig4_white_softening_low": (-6e5, "white", 5e-4, 4),
    "fig5_white_softening_high": (-6e5, "white", 6.5e-4, 5),
    "fig6_kt_hardening_low": (6e7, "kanai_tajimi", 2.5e-4, 6),
    "fig7_kt_hardening_high": (6e7, "kanai_tajimi", 4e-4, 7),
    "fig8_kt_softening_low": (-6e5, "kanai_tajimi", 1.8e-4, 8),
    "fig9_kt_softening_high": (-6e5, "kanai_tajimi", 2e-4, 9),
}


def paper_case(name):
    """``(block, foundation, excitation)`` of a paper case (omega_g = 10 rad/s, zeta_g = 0.4).

    The reference configurations of section 3 of [1]_: the block ``PAPER_BLOCK`` (m = 8.67 kg,
    b = 0.035 m, h = 0.21 m) on the Hunt-Crossley bed ``PAPER_BED`` (k = 2.89e7 N/m^2,
    lam = 8.95e8 N s/m^3) with the case's ``eps``, shaken by a white noise or a Kanai-Tajimi
    process (omega_g = 10 rad/s, zeta_g = 0.4) of intensity ``S0`` under the envelope
    T1 = 4 s, T2 = 2 s.  The ``eps`` values are those of the figure captions.

    Parameters
    ----------
    name : str
        A key of ``PAPER_CASES`` (``"fig2_white_hardening_low"`` ... ``"fig9_kt_softening_high"``).

    Returns
    -------
    block : screening.core.model.Block
        The paper's block (SI units).
    foundation : screening.core.model.Foundation
        The bed, ``eps`` [1/m^2] of the case.
    excitation : screening.core.excitations.white.WhiteNoise or screening.core.excitations.kanai_tajimi.KanaiTajimi
        The ground motion, ``S0`` [m^2/s^3] of the case.

    Raises
    ------
    KeyError
        ``name`` is not a paper case.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] H. Tajimi, "A statistical method of determining the maximum response of a building
       structure during an earthquake", Proc. 2nd World Conference on Earthquake Engineering,
       Tokyo and Kyoto, vol. 2 (1960).
    """
    eps, kind, S0, _ = PAPER_CASES[name]
    block = Block(**PAPER_BLOCK)
    foundation = Foundation(eps=eps, **PAPER_BED)
    if kind == "white":
        excitation = WhiteNoise(S0, Envelope(4.0, 2.0), band_limit_hz=None)          # the paper's: no band
    else:
        excitation = KanaiTajimi(S0, 10.0, 0.4, Envelope(4.0, 2.0), band_limit_hz=None)
    return block, foundation, excitation
