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


def scalar_excitation(kind, envelope_kind, p):
    env = Envelope(p["T1"], p["T2"]) if envelope_kind == "exponential" else ConstantEnvelope()
    return excitations.build(kind, 1.0, p, env)
