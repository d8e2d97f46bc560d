"""Progress of long runs on stderr (no extra dependency): a bar on a terminal, lines in a log."""

from __future__ import annotations

import sys
import threading
import time

__all__ = []

#: Without a terminal (a log file, CI, a pipe): one line per this fraction of the work ...
LINE_STEP = 0.1
#: ... or after this many seconds without one [s]: nothing is silent for longer (a long batch, a compile).
LINE_INTERVAL = 10.0


def _duration(seconds):
    """``42 s``, ``3 min 05 s`` or ``2 h 07 min``."""
    seconds = max(0, int(round(seconds)))
    if seconds < 60:
        return f"{seconds} s"
    if seconds < 3600:
        return f"{seconds // 60} min {seconds % 60:02d} s"
    return f"{seconds // 3600} h {seconds % 3600 // 60:02d} min"


class Progress:
    """``label: 42% (420/1000) 3.1 s, about 4 s left`` on stderr.

    On a terminal the line is redrawn at most every ``interval`` seconds; otherwise (``stream`` not a
    terminal, or ``lines=True``) a new line is written every :data:`LINE_STEP` of the work or
    :data:`LINE_INTERVAL` seconds, and at the end.  A background thread keeps it alive while one
    long task (a spot check) runs.  The time left is the elapsed time per unit of work times the
    units left, or what ``eta()`` says (seconds, or None: not known yet); ``line_interval`` [s]: the
    longest time between lines (default :data:`LINE_INTERVAL`), and with it the first line is written at
    once.  ``clock``: seconds (default ``time.perf_counter``; a fake one in tests).  Silent when
    ``enabled`` is false.  Use as a context manager; call :meth:`update`.
    """

    def __init__(self, total, label="progress", enabled=True, interval=0.5, stream=None, lines=None, eta=None,
                 line_interval=None, clock=None):
        self.total = max(int(total), 1)
        self.label = label
        self.enabled = enabled
        self.interval = interval
        self.stream = stream if stream is not None else sys.stderr
        if lines is None:
            try:
                lines = not self.stream.isatty()
            except (AttributeError, ValueError):
                lines = True
        self.lines = lines
        self.clock = clock if clock is not None else (lambda: time.perf_counter())
        self.eta = eta
        self.line_interval = LINE_INTERVAL if line_interval is None else float(line_interval)
        self._eager = line_interval is not None
        self.done = 0
        self._start = self.clock()
        self._last = -float("inf")
        self._last_step = 0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._ticker = None

    def text(self, now=None):
        """The progress line (without line ending)."""
        elapsed = (self.clock() if now is None else now) - self._start
        pct = 100.0 * self.done / self.total
        head = f"{self.label}: {pct:3.0f}% ({self.done}/{self.total}) {elapsed:.1f} s"
        if self.eta is not None and self.done < self.total:
            left = self.eta()
            return head if left is None else f"{head}, about {_duration(left)} left"
        if 0 < self.done < self.total:
            return f"{head}, about {_duration(elapsed / self.done * (self.total - self.done))} left"
        return head

    def update(self, n=1):
        self.done += n
        if self.enabled:
            self._show(self.done >= self.total)

    def _show(self, finished=False):
        with self._lock:
            now = self.clock()
            if self.lines:
                step = int(self.done / self.total / LINE_STEP + 1e-9)
                if finished or step > self._last_step or now - self._last >= self.line_interval:
                    self._last_step, self._last = step, now
                    self._write(self.text(now) + "\n")
            elif now - self._last >= self.interval or finished:
                self._last = now
                self._write("\r" + self.text(now) + "\033[K")

    def _write(self, text):
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):       # a closed stderr stops the display, not the run
            self.enabled = False

    def _tick(self):
        period = self.line_interval if self.lines else max(self.interval, 1.0)
        while not self._stop.wait(period):
            if self.enabled and self.done < self.total:
                self._show()

    def __enter__(self):
        self._start = self.clock()
        if self.enabled:
            self._ticker = threading.Thread(target=self._tick, name="progress", daemon=True)
            self._ticker.start()
            if self._eager:
                self._show(True)
        return self

    def __exit__(self, *exc):
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join()
        if self.enabled and not self.lines:
            self._write("\n")
        return False
