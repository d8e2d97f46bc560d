"""Nothing silent for more than 10 s (issue 36 item 11): a line when numba compiles a kernel its cache does
not hold, again while compiling goes on, and a progress line at least every 10 s (fake clocks)."""

import io

from screening import progress
from screening.kernels.cache import COMPILE_INTERVAL, CompileAnnouncer, announcing_compiles


class Clock:
    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def test_a_compile_is_announced_then_repeated_while_it_lasts():
    out, clock = io.StringIO(), Clock()
    a = CompileAnnouncer(out, clock=clock)
    a.started("_solve_batch")
    lines = out.getvalue().splitlines()
    assert len(lines) == 1 and "compiling _solve_batch" in lines[0]
    for second in range(1, 61):                              # one minute of compiling, ticked each second
        clock.now = float(second)
        a.tick()
    times = [0.0] + [float(line.rsplit(", ", 1)[1].split()[0]) for line in out.getvalue().splitlines()[1:]]
    assert len(times) >= 6 and max(b - t for t, b in zip(times, times[1:] + [60.0])) <= COMPILE_INTERVAL <= 10
    a.finished()
    before = out.getvalue()
    clock.now = 200.0
    a.tick()                                                 # nothing compiles: nothing said
    assert out.getvalue() == before


def test_numba_compiles_are_heard(tmp_path):
    """The announcer hears numba's own event: a fresh function compiled inside the context is named."""
    import numba

    out = io.StringIO()

    @numba.njit
    def add_one(x):
        return x + 1

    with announcing_compiles(stream=out):
        assert add_one(1) == 2
    assert "compiling" in out.getvalue() and "add_one" in out.getvalue()
    with announcing_compiles(quiet=True, stream=out) as quiet:
        assert quiet.announcer is None


def test_progress_lines_come_at_least_every_ten_seconds():
    out, clock = io.StringIO(), Clock()
    assert progress.LINE_INTERVAL <= 10.0
    bar = progress.Progress(8, label="points", stream=out, lines=True, clock=clock)
    bar._start = 0.0
    for second in range(1, 41):                              # no point finishes for 40 s: the ticker shows
        clock.now = float(second)
        bar._show()
    stamps = [float(line.split(") ")[1].split(" s")[0]) for line in out.getvalue().splitlines()]
    assert stamps and max(b - a for a, b in zip([0.0] + stamps, stamps + [40.0])) <= 10.0
