"""The registry of condensations: a name is turned into a :class:`~screening.core.condensation.base.Condensation`
once, at set-up (study parsing, ``linearize``, ``monte_carlo``); nothing downstream looks at the name."""

from __future__ import annotations

from screening.core.condensation.base import Condensation
from screening.core.registry import Registry

__all__ = ["DEFAULT_CONDENSATION", "unregister", "names", "get", "register"]

#: The condensation used wherever none is chosen: ``linearize``, the study file's
#: ``foundation.condensation``, the condensed Monte Carlo model, :mod:`screening.core.condensation.api`
#: and the command line.  ``"virtual_work"``: on the error atlas it is within 25 % of the
#: reference at more points than ``"paper"`` and ``"cubic"`` below a peak ``p_uplift`` of 0.95, and
#: where it stops (``k_eq_negative``) the block topples (docs/error_atlas.md).  The paper's own
#: condensation is ``"paper"``: pin it to reproduce the paper.
DEFAULT_CONDENSATION = "virtual_work"

_REGISTRY = Registry("condensation", lambda item: isinstance(item, Condensation))

#: Remove a registered condensation (tests that register their own).
unregister = _REGISTRY.remove
#: Registered names, in registration order.
names = _REGISTRY.names
#: The :class:`Condensation` for a registered name (an instance is returned as it is); ``ValueError``
#: naming the parameter and the registered names otherwise.
get = _REGISTRY.get


def register(condensation):
    """Add a :class:`Condensation` instance under its ``name`` (a later one with the same name replaces it).

    Parameters
    ----------
    condensation : Condensation
        The condensation (an instance of a
        :class:`~screening.core.condensation.base.Condensation` subclass).

    Returns
    -------
    Condensation
        ``condensation`` itself.

    Raises
    ------
    TypeError
        For anything that is not a ``Condensation`` instance.

    References
    ----------
    .. [1] I. P. Mitseas, "Nonlinear dynamics of rocking rigid blocks under stochastic base excitation:
       A stochastic-linearization approach", Journal of Sound and Vibration (2026) 119733.
       https://doi.org/10.1016/j.jsv.2026.119733 (the paper's condensation, eqs. 13-22).

    Examples
    --------
    >>> paper = get("paper")
    >>> register(paper) is paper, names()[0]
    (True, 'paper')
    >>> register("paper")
    Traceback (most recent call last):
    ...
    TypeError: register() takes a Condensation instance (got str)
    """
    if not isinstance(condensation, Condensation):
        raise TypeError(f"register() takes a Condensation instance (got {type(condensation).__name__})")
    return _REGISTRY.add(condensation.name, condensation)
