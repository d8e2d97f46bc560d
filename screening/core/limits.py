"""Bounds on what a study, a record or an API call may ask for, checked before any work.

Every size a study sets — grid points, output steps, Monte Carlo samples, the seed — is checked
against the limits below *before* any array is built, so that a typo such as ``num = 1e9`` or
``dt = 1e-9`` is a one-line :class:`~screening.sweep.config.StudyError` naming the key and the
allowed range, never a MemoryError, an OverflowError or a cluster that starts and dies.

Only the grid size is configurable (``[run] max_points``, itself at most
:data:`MAX_POINTS_CEILING`); the other limits are far beyond any screening study and only keep
the memory of one task (one batch of points, one spot check) bounded.
"""

from __future__ import annotations

import math

__all__ = []

#: Default largest grid (``case`` x swept parameters); ``[run] max_points`` changes it.
DEFAULT_MAX_POINTS = 1_000_000
#: Largest ``[run] max_points`` accepted.
MAX_POINTS_CEILING = 100_000_000
#: Most output instants (``t_end / dt + 1``).
MAX_TIMES = 100_001
#: Most Monte Carlo samples of one spot check.
MAX_SAMPLES = 1_000_000
#: Most ``samples x output instants`` of one spot check (about 17 bytes each: ~0.9 GB).
MAX_SAMPLE_VALUES = 50_000_000
#: Grid points of one synthesized Monte Carlo sample at most (its complex FFT: 134 MB): bounds the band an
#: excitation may carry over a record (screening.solvers.synthesis.max_band_limit_hz).
MAX_SYNTHESIS_POINTS = 2**23
#: Seeds are stored as int32 (``mcs_seed``): ``0 .. 2**31 - 1``.
MAX_SEED = 2**31 - 1
#: Largest study file [characters] (a study is a page of TOML).
MAX_STUDY_CHARS = 1_000_000
#: Deepest nesting of tables/arrays in a study file (TOML's parser recurses).
MAX_NESTING = 50
#: Most history values (points x output instants x variables) one linearization call holds (0.8 GB).
MAX_HISTORY_VALUES = 100_000_000
#: Loosest relative tolerance of the adaptive integrators (a looser one gives no accuracy worth the name).
MAX_RTOL = 1e-2
#: Memory budget of the time histories of one linearization task [bytes].
TASK_BYTES = 256 * 2**20
#: Most ``[[case]]`` tables of a study (each is validated on its own).
MAX_CASES = 1_000
#: Most ``[fragility] thresholds`` (each costs a pass over the grid).
MAX_THRESHOLDS = 100
#: Largest study file [bytes] read (UTF-8: at most 4 bytes per character).
MAX_STUDY_BYTES = 4 * MAX_STUDY_CHARS
#: Largest record file [bytes] read (2 million samples in two columns of 15 digits; a
#: strong-motion record is a few MB).
MAX_RECORD_BYTES = 64 * 2**20
#: Most samples of one record (and output instants of one simulation): 2.8 h at 200 Hz.
MAX_RECORD_SAMPLES = 2_000_000
#: Time step of a record [s]: ``MIN_RECORD_DT <= dt <= MAX_RECORD_DT``.
MIN_RECORD_DT = 1e-6
MAX_RECORD_DT = 1.0
#: Factor on a record's accelerations (``--scale``, ``[records] scale``): ``0 < |scale| <= MAX_RECORD_SCALE``.
MAX_RECORD_SCALE = 1_000.0
#: Most record files of one cloud analysis.
MAX_RECORD_FILES = 100_000
#: Oscillator periods of Sa(T, 5 %) of a record [s] (``[records] period``).
SA_PERIOD_RANGE = (1e-3, 100.0)
#: Largest modelling dispersion beta_m [1] (``screening fragility --modelling-dispersion``): FEMA P-58 uses
#: 0.1-0.6; beyond a few units a lognormal capacity has no meaning (and exp(beta^2) overflows near 26.6).
MAX_MODELLING_DISPERSION = 3.0


def nesting_depth(text):
    """Upper bound of the nesting depth of ``text``: ``[``/``{`` and the parts of dotted keys
    (``a.b.c = 1``, ``[a.b.c]``), outside strings and comments.

    A quick scan (not a TOML parser): brackets in strings and comments are skipped so that a
    title such as ``"[[[["`` does not count, and dots count only in keys (not in ``1.5``); it
    only needs to be an upper bound of what the parser will build, cheap on any input.

    Parameters
    ----------
    text : str
        A study file's text (TOML).

    Returns
    -------
    int
        An upper bound of its nesting depth [-], compared with :data:`MAX_NESTING`.

    """
    depth = deepest = dots = 0
    stack = []                      # "[" of a table header, "a" of an array, "{" of an inline table
    in_key = True                   # at the start of a line, after "{" or "," of an inline table
    i, n = 0, len(text)
    while i < n:
        ch = text[i]
        if ch == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j
            continue
        if ch in "\"'":
            i = _string_end(text, i)
            continue
        if ch == "\n":
            if not stack:
                in_key, dots = True, 0
        elif ch == "." and (in_key or (stack and stack[-1] == "[")):
            dots += 1
            deepest = max(deepest, depth + dots + 1)
        elif ch == "=" and in_key:
            in_key, dots = False, 0
        elif ch == "[":
            stack.append("[" if in_key and not stack or stack and stack[-1] == "[" else "a")
            depth += 1
        elif ch == "{":
            stack.append("{")
            depth += 1
            in_key, dots = True, 0
        elif ch in "]}":
            if stack:
                stack.pop()
            depth = max(depth - 1, 0)
            if not stack or stack[-1] != "{":
                in_key = False
        elif ch == "," and stack and stack[-1] == "{":
            in_key, dots = True, 0
        deepest = max(deepest, depth)
        i += 1
    return deepest


def _string_end(text, i):
    """Index just after the TOML string that starts at ``text[i]`` (a quote)."""
    ch, n = text[i], len(text)
    triple = text.startswith(ch * 3, i)
    end = ch * 3 if triple else ch
    j = i + len(end)
    while j < n:
        if ch == '"' and text[j] == "\\":
            j += 2
            continue
        if text.startswith(end, j):
            break
        if not triple and text[j] == "\n":
            break
        j += 1
    return j + len(end)


def output_steps(t_end, dt):
    """``t_end / dt`` as a float (``inf`` when it overflows); no array is built.

    Parameters
    ----------
    t_end : float
        The end time of the output [s].
    dt : float
        The output time step [s].

    Returns
    -------
    float
        The number of output steps [-] (the output has one instant more), compared with
        :data:`MAX_TIMES`; ``inf`` for ``dt = 0`` or an overflow.

    """
    try:
        ratio = t_end / dt
    except (OverflowError, ZeroDivisionError):
        return math.inf
    return ratio


def batch_budget(n_times, n_variables=6, budget=TASK_BYTES):
    """Most points per task whose time histories (``n_variables`` float64 per instant) fit ``budget``.

    Parameters
    ----------
    n_times : int
        Output instants per point [-].
    n_variables : int, default 6
        Histories stored per point [-].
    budget : int, default TASK_BYTES
        Memory of one task's histories [bytes] (256 MiB).

    Returns
    -------
    int
        ``budget // (8 n_times n_variables)``, at least 1 [-].

    """
    return max(1, int(budget // (8 * max(int(n_times), 1) * max(int(n_variables), 1))))
