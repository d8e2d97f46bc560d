"""Nothing silent for more than 10 s (issue 36 item 11): a line when numba compiles a kernel its cache does
not hold, again while compiling goes on, and a progress line at least every 10 s (fake clocks)."""

import io

from screening.core import progress
from screening.kernels.cache import COMPILE_DELAY, COMPILE_INTERVAL, CompileAnnouncer, announcing_compiles


class Clock:
    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def test_a_compile_is_announced_then_repeated_while_it_lasts():
    out, clock = io.StringIO(), Clock()
    a = CompileAnnouncer(out, clock=clock)
    a.started("_solve_batch")
    for second in range(1, 61):                              # one minute of compiling, ticked each second
        clock.now = float(second)
        a.tick()
    lines = out.getvalue().splitlines()
    assert "compiling _solve_batch" in lines[0]
    times = [COMPILE_DELAY] + [float(line.rsplit(", ", 1)[1].split()[0]) for line in lines[1:]]
    assert times[0] <= 2.0 and len(times) >= 6
    assert max(b - t for t, b in zip(times, times[1:] + [60.0])) <= COMPILE_INTERVAL <= 10
    a.finished()
    before = out.getvalue()
    clock.now = 200.0
    a.tick()                                                 # nothing compiles: nothing said
    assert out.getvalue() == before


def test_a_short_compile_is_not_announced():
    out, clock = io.StringIO(), Clock()
    a = CompileAnnouncer(out, clock=clock)
    a.started("small")
    clock.now = 0.5
    a.finished()
    for second in range(1, 30):
        clock.now = float(second)
        a.tick()
    assert out.getvalue() == ""


def test_the_lines_name_the_outermost_compile():
    """Helpers compiled on the way (numba's own implementations among them) do not take the kernel's name."""
    out, clock = io.StringIO(), Clock()
    a = CompileAnnouncer(out, clock=clock)
    a.started("integrate_chunk")
    a.started("ol_min.<locals>.impl")
    clock.now = 3.0
    a.tick()
    a.finished()
    a.finished()
    a.started("_record")                                     # a new outermost compile: its own name
    clock.now = 14.0
    a.tick()
    lines = out.getvalue().splitlines()
    assert "compiling integrate_chunk" in lines[0] and "now _record" in lines[1]


def test_numba_compiles_are_heard(monkeypatch):
    """The announcer hears numba's own event: a fresh function compiled inside the context is named."""
    import numba

    from screening.kernels import cache

    monkeypatch.setattr(cache, "COMPILE_DELAY", 0.0)
    heard = []
    monkeypatch.setattr(cache.CompileAnnouncer, "started", lambda self, name: heard.append(name))
    monkeypatch.setattr(cache.CompileAnnouncer, "finished", lambda self: heard.append("done"))

    @numba.njit
    def add_one(x):
        return x + 1

    with announcing_compiles(stream=io.StringIO()):
        assert add_one(1) == 2
    assert any("add_one" in name for name in heard) and heard[-1] == "done"
    with announcing_compiles(quiet=True) as quiet:
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
