"""Progress of a long run or study: a bar on a terminal, lines elsewhere.

Output that is not a terminal (CI, ``nohup``, a pipe) gets no bar (its carriage returns would be
one endless line) but a line every :data:`INTERVAL` seconds and one when the count is complete,
so that a 25-minute report shows signs of life in a log: a beat of its own says the line while
nothing finishes (a study's 3D run of ten minutes), the time left counting down from the last
estimate.
"""

from __future__ import annotations

import sys
import threading
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
    beat : real seconds between two looks of the beat at the clock (lines mode)
    """

    def __init__(self, total: int, desc: str, unit: str, enabled: bool = True, stream=None, clock=time.monotonic,
                 leave: bool = True, beat: float = INTERVAL / 2):
        self.total, self.desc, self.unit = total, desc, unit
        self.stream = stream or sys.stderr
        self.clock = clock
        self.n, self.note = 0, ""
        self._left = None  # (seconds left, the clock when said) or None
        self._bar = None
        self._lines = False
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._beat = None
        if enabled and total > 0:
            if self.stream.isatty():
                from tqdm import tqdm

                self._bar = tqdm(total=total, desc=desc, unit=unit, file=self.stream, leave=leave)
            else:
                self._lines = True
                self._start = self._last = clock()
                self._beat = threading.Thread(target=self._beating, args=(beat,), daemon=True)
                self._beat.start()

    def update(self, n: int, note: str = "", left_s: float | None = None) -> None:
        """``n`` done so far; ``note``: what just finished; ``left_s``: an estimate of the
        seconds left (said as "about ... left"), where the caller has one."""
        with self._lock:
            step, self.n, self.note = n - self.n, n, note or self.note
            self._left = None if left_s is None or n >= self.total else (left_s, self.clock())
            if self._bar is not None:
                left = self.left
                if note or left:
                    self._bar.set_postfix_str(", ".join(x for x in (left, note) if x), refresh=False)
                self._bar.update(step)
            elif self._lines and self.clock() - self._last >= INTERVAL and n < self.total:
                self._line()

    @property
    def left(self) -> str:
        """``about 12 min left``: the last estimate less the time since; '' without one or once
        it has run out."""
        if self._left is None:
            return ""
        seconds = self._left[0] - (self.clock() - self._left[1])
        return f"about {_duration(seconds)} left" if seconds >= 1 else ""

    def _beating(self, beat: float) -> None:
        while not self._stop.wait(beat):
            with self._lock:
                if self._lines and self.clock() - self._last >= INTERVAL and self.n < self.total:
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
        self._stop.set()
        if self._beat is not None:
            self._beat.join()
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
