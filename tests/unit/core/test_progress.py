"""Progress on stderr: lines in a log (every 10 % or 10 s, with the time left), a bar on a terminal."""

import io

from screening.core import progress
from screening.core.progress import Progress


class _Clock:
    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def test_a_log_gets_a_line_every_tenth_with_the_time_left(monkeypatch):
    clock = _Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    stream = io.StringIO()                                    # not a terminal
    with Progress(1000, label="points", stream=stream) as bar:
        for _ in range(100):
            clock.now += 0.5
            bar.update(10)
    lines = stream.getvalue().splitlines()
    assert len(lines) == 11 and "\r" not in stream.getvalue()     # the first update, then each tenth
    assert lines[1] == "points:  10% (100/1000) 5.0 s, about 45 s left"
    assert lines[-1] == "points: 100% (1000/1000) 50.0 s"


def test_a_log_gets_a_line_after_10_s_without_a_tenth(monkeypatch):
    clock = _Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    stream = io.StringIO()
    with Progress(1000, label="points", stream=stream) as bar:
        clock.now = 1.0
        bar.update(1)                      # first update: a line (first report)
        clock.now = 10.0
        bar.update(1)                      # neither a tenth nor 10 s later: nothing
        clock.now = 40.0
        bar.update(1)                      # more than 10 s after the last line
    lines = stream.getvalue().splitlines()
    assert len(lines) == 2 and lines[1].startswith("points:   0% (3/1000) 40.0 s, about 3 h")


def test_a_terminal_gets_one_redrawn_line_with_the_time_left(monkeypatch):
    clock = _Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    stream = io.StringIO()
    with Progress(4, label="spot checks", stream=stream, lines=False) as bar:
        for _ in range(4):
            clock.now += 90.0
            bar.update(1)
    text = stream.getvalue()
    assert text.count("\n") == 1 and text.endswith("\n")
    assert "\rspot checks:  25% (1/4) 90.0 s, about 4 min 30 s left" in text


def test_disabled_is_silent():
    stream = io.StringIO()
    with Progress(10, stream=stream, enabled=False) as bar:
        bar.update(10)
    assert stream.getvalue() == ""
