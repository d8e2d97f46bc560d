"""The shape of an excitation as the random-vibration intensity measures cache it (package-internal;
shared by :mod:`screening.analysis.intensity_rvt` and :mod:`screening.analysis.intensity`): the times
the non-stationary moments are evaluated on, the cache key of an excitation's shape (filter kind,
envelope, record length) and the excitation of unit level rebuilt from its parameters.
"""

from __future__ import annotations

import numpy as np
from screening.core import excitations
from screening.core.model.excitation import ConstantEnvelope, Envelope

#: Times on which the non-stationary moments are evaluated over ``[0, t_end]``.
N_TIMES = 4001


def times(t_end, n=N_TIMES):
    return np.linspace(0.0, float(t_end), n)


def shape_key(excitation, t_end):
    """Cache key of the filter kind, envelope and record length of ``excitation``."""
    env = excitation.envelope
    return (excitation.kind, env.kind, *(np.atleast_1d(env.params[1:]).astype(float).tolist()
                                         if env.kind == "exponential" else ()), float(t_end))


def shape_names(excitation):
    """The fields that make an excitation's shape besides its envelope: its filter parameters and, with a
    band, ``band_limit_hz``."""
    band = () if getattr(excitation, "band_limit_hz", None) is None else ("band_limit_hz",)
    return tuple(excitation.parameters) + band


def scalar_excitation(kind, envelope_kind, p):
    """The excitation of unit level of the shape ``p`` (filter parameters, ``T1``, ``T2`` and, with a band,
    ``band_limit_hz``; without it, or NaN, the idealized spectrum)."""
    env = Envelope(p["T1"], p["T2"]) if envelope_kind == "exponential" else ConstantEnvelope()
    band = p.get("band_limit_hz")
    band = None if band is None or not np.isfinite(band) else float(band)
    return excitations.build(kind, 1.0, p, env, band_limit_hz=band)


def distinct_points(columns, shape):
    """``[(values, flat indices)]``: the points of ``shape`` grouped by their values of ``columns`` (arrays
    broadcast to ``shape``; ``values`` a tuple of floats), one ``numpy.unique`` instead of a key per point."""
    n = int(np.prod(shape, dtype=int))
    if not columns:
        return [((), np.arange(n))]
    rows = np.stack([np.broadcast_to(np.asarray(c, dtype=float), shape).reshape(n) for c in columns], axis=1)
    if np.all(rows == rows[:1]):                        # one shape for the whole batch (the usual case)
        return [(tuple(float(v) for v in rows[0]), np.arange(n))]
    distinct, inverse = np.unique(rows, axis=0, return_inverse=True)
    inverse = inverse.reshape(n)
    return [(tuple(float(v) for v in row), np.flatnonzero(inverse == j)) for j, row in enumerate(distinct)]
