"""The registry of excitations, filled by subclassing :class:`Excitation` with a ``kind``: a kind is turned into
its class at set-up (study parsing, result readers); the solvers use the object's filter and PSD, never its kind."""

from __future__ import annotations

from screening.core.excitations.base import GROUND_BAND_LIMIT_HZ, Excitation, KINDS

__all__ = ["register", "unregister", "names", "get", "parameters", "build"]

_REGISTRY = KINDS


def register(cls):
    """Add an :class:`Excitation` subclass under its ``kind`` (a subclass declaring its ``kind`` is added when
    defined); a later class with the same ``kind`` replaces the earlier one.

    Parameters
    ----------
    cls : type
        A subclass of :class:`~screening.core.excitations.base.Excitation` whose ``kind`` [-] is a
        non-empty string.

    Returns
    -------
    type
        ``cls`` itself, so the function decorates a class definition.

    Raises
    ------
    TypeError
        For anything that is not an ``Excitation`` subclass with a ``kind``.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md`` (the excitations of eqs. 47-50).

    Examples
    --------
    >>> from screening.core.excitations.kanai_tajimi import KanaiTajimi
    >>> register(KanaiTajimi) is KanaiTajimi, "kanai_tajimi" in names()
    (True, True)
    >>> register(int)
    Traceback (most recent call last):
    ...
    TypeError: register() takes an Excitation subclass with a kind (got <class 'int'>)
    """
    if not (isinstance(cls, type) and issubclass(cls, Excitation)) or not cls.kind:
        raise TypeError(f"register() takes an Excitation subclass with a kind (got {cls!r})")
    return _REGISTRY.add(cls.kind, cls)


#: Remove a registered excitation (tests that register their own).
unregister = _REGISTRY.remove
#: Registered kinds, in registration order.
names = _REGISTRY.names
#: The excitation class of a registered ``kind``; ``ValueError`` naming the registered kinds otherwise.
get = _REGISTRY.get


def parameters():
    """The parameters of every registered excitation (the first declaration of a name wins).

    Returns
    -------
    dict of str to Parameter
        ``{name: Parameter}``: each filter parameter with its units (e.g. ``omega_g`` [rad s-1],
        ``zeta_g`` [1]) and long name, in registration order.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md`` (the filter parameters of eqs. 48-50).

    Examples
    --------
    >>> p = parameters()
    >>> list(p)[:2], p["omega_g"].units
    (['omega_g', 'zeta_g'], 'rad s-1')
    """
    out = {}
    for cls in _REGISTRY.values():
        for name, p in cls.parameters.items():
            out.setdefault(name, p)
    return out


def build(kind, S0, params, envelope, band_limit_hz=GROUND_BAND_LIMIT_HZ):
    """An excitation of a registered ``kind``, its filter parameters taken by name from ``params``.

    Parameters
    ----------
    kind : str
        A registered kind (:func:`names`), e.g. ``"kanai_tajimi"``.
    S0 : float
        Two-sided PSD level of the driving white noise [m2 s-3], > 0.
    params : mapping of str to float
        The values of the kind's parameters in SI units (``omega_g`` [rad s-1], ``zeta_g`` [1], ...);
        extra names are ignored.
    envelope : Envelope or ConstantEnvelope
        The modulating function ``q(t)`` [1].
    band_limit_hz : float or None, optional
        Corner of the band's low-pass [Hz] (default :data:`~screening.core.excitations.base.GROUND_BAND_LIMIT_HZ`);
        None: the idealized spectrum.

    Returns
    -------
    Excitation
        An instance of the registered class.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md`` (eqs. 47-50).

    Examples
    --------
    >>> from screening.core.model.excitation import ConstantEnvelope
    >>> build("kanai_tajimi", 0.01, {"omega_g": 15.0, "zeta_g": 0.6, "omega_f": 1.0}, ConstantEnvelope())
    KanaiTajimi(S0=0.01, omega_g=15.0, zeta_g=0.6, envelope=ConstantEnvelope(), band_limit_hz=25.0)
    """
    cls = get(kind)
    return cls(S0, *(params[name] for name in cls.parameters), envelope=envelope, band_limit_hz=band_limit_hz)
