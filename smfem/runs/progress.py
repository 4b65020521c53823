"""Progress of a long run or study: a bar on a terminal, lines elsewhere.

Output that is not a terminal (CI, ``nohup``, a pipe) gets no bar (its carriage returns would be
one endless line) but a line every :data:`INTERVAL` seconds and one when the count is complete,
so that a 25-minute report shows signs of life in a log.
"""

from __future__ import annotations

import sys
import time

#: seconds between two progress lines when the output is not a terminal
INTERVAL = 10.0


class Progress:
    """``update(n, note)`` with the count done so far; ``close()`` at the end.

    Parameters
    ----------
    total : the count at the end
    desc : what progresses (``'study'``, ``'dome (smfem)'``)
    unit : of the count (``'run'``, ``'step'``)
    enabled : False: silent (``--quiet``)
    stream : default stderr
    clock : seconds, for tests (default ``time.monotonic``)
    """

    def __init__(self, total: int, desc: str, unit: str, enabled: bool = True, stream=None, clock=time.monotonic,
                 leave: bool = True):
        self.total, self.desc, self.unit = total, desc, unit
        self.stream = stream or sys.stderr
        self.clock = clock
        self.n, self.note, self.left = 0, "", ""
        self._bar = None
        self._lines = False
        if enabled and total > 0:
            if self.stream.isatty():
                from tqdm import tqdm

                self._bar = tqdm(total=total, desc=desc, unit=unit, file=self.stream, leave=leave)
            else:
                self._lines = True
                self._start = self._last = clock()

    def update(self, n: int, note: str = "", left_s: float | None = None) -> None:
        """``n`` done so far; ``note``: what just finished; ``left_s``: an estimate of the
        seconds left (said as "about ... left"), where the caller has one."""
        step, self.n, self.note = n - self.n, n, note or self.note
        self.left = "" if left_s is None or n >= self.total else f"about {_duration(left_s)} left"
        if self._bar is not None:
            if note or self.left:
                self._bar.set_postfix_str(", ".join(x for x in (self.left, note) if x), refresh=False)
            self._bar.update(step)
        elif self._lines and self.clock() - self._last >= INTERVAL and n < self.total:
            self._line()

    def grow(self, more: int) -> None:
        """``more`` to do than the total said (a study's runs asked for as others finish)."""
        if more <= 0:
            return
        self.total += more
        if self._bar is not None:
            self._bar.total = self.total
            self._bar.refresh()

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
        elif self._lines:
            if self.n >= self.total:  # finished: a failure says so in its own one line
                self._line()
            self._lines = False

    def _line(self) -> None:
        self._last = self.clock()
        note = f" ({self.note})" if self.note else ""
        left = f", {self.left}" if self.left else ""
        print(f"{self.desc}: {self.n}/{self.total} {self.unit}s, {self._last - self._start:.0f} s{left}{note}",
              file=self.stream, flush=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _duration(seconds: float) -> str:
    """``40 s``, ``12 min``, ``2.5 h``."""
    if seconds < 90:
        return f"{max(seconds, 1):.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"
