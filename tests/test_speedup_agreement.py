"""benchmarks/speedup_agreement.py's run-level view of two retimes: which runs moved, and whether
the host's memory probe moved under them."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from tests.test_benchmarks import load

AGREEMENT = load(Path(__file__).resolve().parents[1] / "benchmarks" / "speedup_agreement.py")


def repeats(rows):
    return pd.DataFrame(rows, columns=["case", "solver", "label", "cpu_s", "host_probe_s"])


def test_a_run_whose_least_moved_is_listed_with_the_probe_under_it_and_one_that_held_is_not():
    a = repeats([("strip", "reference-2d", "r1", 20.0, 0.011), ("strip", "reference-2d", "r1", 21.0, 0.012),
                 ("strip", "smfem", "r1 H120", 0.70, 0.011), ("strip", "smfem", "r1 H120", 0.72, 0.011)])
    b = repeats([("strip", "reference-2d", "r1", 26.0, 0.019), ("strip", "reference-2d", "r1", 27.0, 0.020),
                 ("strip", "smfem", "r1 H120", 0.71, 0.019)])
    lines = AGREEMENT.moved_runs(a, b, 0.10)
    assert lines == ["strip reference-2d r1: least 20 -> 26 s (+30.0 %, 2 and 2 repeats), probe median 11.5 -> 19.5 ms"]
    assert AGREEMENT.moved_runs(a, a, 0.10) == []
