"""Bounds on what a study may ask for, checked while the study file is parsed.

Every size a study sets — grid points, output steps, Monte Carlo samples, the seed — is checked
against the limits below *before* any array is built, so that a typo such as ``num = 1e9`` or
``dt = 1e-9`` is a one-line :class:`~screening.workflow.config.StudyError` naming the key and the
allowed range, never a MemoryError, an OverflowError or a cluster that starts and dies.

Only the grid size is configurable (``[run] max_points``, itself at most
:data:`MAX_POINTS_CEILING`); the other limits are far beyond any screening study and only keep
the memory of one task (one batch of points, one spot check) bounded.
"""

from __future__ import annotations

import math

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
#: Seeds are stored as int32 (``mcs_seed``): ``0 .. 2**31 - 1``.
MAX_SEED = 2**31 - 1
#: Largest study file [characters] (a study is a page of TOML).
MAX_STUDY_CHARS = 1_000_000
#: Deepest nesting of tables/arrays in a study file (TOML's parser recurses).
MAX_NESTING = 50
#: Memory budget of the time histories of one linearization task [bytes].
TASK_BYTES = 256 * 2**20


def nesting_depth(text):
    """Upper bound of the nesting depth of ``[``/``{`` in ``text`` outside strings and comments.

    A quick scan (not a TOML parser): brackets in strings and comments are skipped so that a
    title such as ``"[[[["`` does not count; it only needs to be an upper bound of what the
    parser will recurse into, cheap on any input.
    """
    depth = deepest = 0
    i, n = 0, len(text)
    while i < n:
        ch = text[i]
        if ch == "#":
            j = text.find("\n", i)
            i = n if j < 0 else j
            continue
        if ch in "\"'":
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
            i = j + len(end)
            continue
        if ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif ch in "]}":
            depth = max(depth - 1, 0)
        i += 1
    return deepest


def output_steps(t_end, dt):
    """``t_end / dt`` as a float (``inf`` when it overflows); no array is built."""
    try:
        ratio = t_end / dt
    except (OverflowError, ZeroDivisionError):
        return math.inf
    return ratio


def batch_budget(n_times, n_variables=6, budget=TASK_BYTES):
    """Most points per task whose time histories (``n_variables`` float64 per instant) fit ``budget``."""
    return max(1, int(budget // (8 * max(int(n_times), 1) * max(int(n_variables), 1))))
