"""Progress where the output is not a terminal: a line every 10 s and one at the end."""

from __future__ import annotations

import io

from runs.progress import INTERVAL, Progress


class _Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def test_lines_every_interval_and_at_the_end_when_not_a_terminal():
    out, clock = io.StringIO(), _Clock()
    with Progress(100, "study", "run", stream=out, clock=clock) as bar:
        for n in range(1, 101):
            clock.t = n * INTERVAL / 4  # four updates per interval
            bar.update(n, f"run {n}")
    lines = out.getvalue().splitlines()
    assert len(lines) == 25  # 24 while running (the last update is the end's), 1 at the end
    assert lines[0] == "study: 4/100 runs, 10 s (run 4)"
    assert lines[-1] == "study: 100/100 runs, 250 s (run 100)"
    assert "\r" not in out.getvalue()


def test_quiet_prints_nothing():
    out = io.StringIO()
    with Progress(3, "dome (smfem)", "step", enabled=False, stream=out) as bar:
        bar.update(3)
    assert out.getvalue() == ""


def test_an_unfinished_count_leaves_the_last_word_to_its_error():
    out, clock = io.StringIO(), _Clock()
    with Progress(600, "rod_impact (calculix)", "step", stream=out, clock=clock) as bar:
        bar.update(0)
    assert out.getvalue() == ""
