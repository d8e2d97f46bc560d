"""A minimal text progress bar on stderr for long runs (no extra dependency)."""

from __future__ import annotations

import sys
import time


class Progress:
    """Print ``label: 42% (420/1000) 3.1 s`` on stderr, at most every ``interval`` seconds.

    Silent when ``enabled`` is false.  Use as a context manager; call :meth:`update`.
    """

    def __init__(self, total, label="progress", enabled=True, interval=0.5, stream=None):
        self.total = max(int(total), 1)
        self.label = label
        self.enabled = enabled
        self.interval = interval
        self.stream = stream if stream is not None else sys.stderr
        self.done = 0
        self._start = time.perf_counter()
        self._last = -float("inf")

    def update(self, n=1):
        self.done += n
        now = time.perf_counter()
        if self.enabled and (now - self._last >= self.interval or self.done >= self.total):
            self._last = now
            pct = 100.0 * self.done / self.total
            self.stream.write(f"\r{self.label}: {pct:3.0f}% ({self.done}/{self.total}) {now - self._start:.1f} s")
            self.stream.flush()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self.enabled:
            self.stream.write("\n")
            self.stream.flush()
        return False
