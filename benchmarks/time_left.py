"""How well a study's progress says the time left, replayed on a finished study's run cache.

    python benchmarks/time_left.py --cache out/report/cache [--workers 2] [--tiny]

The runs are taken in the order they finished (their cache entries' times), as a study on an
empty cache saw them: at each finished run, :class:`smfem.studies.eta.TimeLeft` predicts the
runs still to come from the finished ones alone (no earlier wall times), and the prediction is
compared with the time the study actually took from there (the last entry's time). Printed at a
twentieth, a tenth, a quarter, half, three quarters and nine tenths of the runs: the ratio predicted /
actual. The study's runs asked for later (a carried ladder's next levels) are counted as known
from the start here, so the early ratios are a little higher than the study's own were.
``--tiny``: a study of four small runs made here first (the tests run every benchmark so).
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

from smfem.runs import threads
from smfem.studies.cache import Run, RunCache
from smfem.studies.eta import TimeLeft
from smfem.studies.jobs import Job

MARKS = (0.05, 0.1, 0.25, 0.5, 0.75, 0.9)


class _NoEarlierRuns:
    """A cache that has never seen a run: every prediction comes from the replayed study."""

    def previous_wall(self, job):
        return None


def finished_runs(root: Path) -> list[tuple[float, Job, dict]]:
    """``(finish time, job, summary)`` of every finished run in the cache at ``root``, in order."""
    runs = []
    for path in root.glob("*/*/*/job.json"):
        try:
            record = json.loads(path.read_text())
            summary = json.loads((path.parent / "summary.json").read_text())
            key = record["key"]
            job = Job.make(key["case"], key["solver"], record["overrides"], options=dict(key.get("options") or {}))
            job.resolved  # a case this code cannot build any more: left out
        except (OSError, ValueError, KeyError, TypeError):
            continue
        runs.append((path.stat().st_mtime, job, summary))
    return sorted(runs, key=lambda r: r[0])


def replay(runs: list[tuple[float, Job, dict]], workers: int) -> list[tuple[int, float, float]]:
    """``(runs finished, predicted s, actual s)`` at each mark."""
    left = TimeLeft(_NoEarlierRuns(), workers)
    left.expect([job for _, job, _ in runs])
    end, rows, marks = runs[-1][0], [], [max(1, round(m * len(runs))) for m in MARKS]
    for n, (t, job, summary) in enumerate(runs, start=1):
        left.finished(job, Run(job, "ok", "", None, None, summary))
        if n in marks:
            rows.append((n, left.seconds() or float("nan"), end - t))
    return rows


def _tiny_cache(root: Path) -> Path:
    from smfem.studies.study import run_cached

    cache = RunCache(root)
    jobs = [Job.make("thick_cylinder", "smfem", {"refine": r, "t_end": 2e-4}) for r in (1, 2, 3)]
    run_cached(jobs + [Job.make("dome", "smfem", {"t_end": 5e-5})], cache, workers=1, progress=False)
    return root


def main(argv=None):
    threads.pin()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", type=Path, help="a study's run cache (OUT/cache of smfem report or study)")
    ap.add_argument("--workers", type=int, default=2, help="the workers the study ran on")
    ap.add_argument("--tiny", action="store_true", help="replay a study of four small runs made here")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        root = _tiny_cache(Path(tmp)) if args.tiny else args.cache
        if root is None or not root.is_dir():
            ap.error("--cache DIR: a run cache (or --tiny)")
        runs = finished_runs(root)
        if len(runs) < 2:
            ap.error(f"{root}: fewer than two finished runs")
        print(f"{len(runs)} runs, {runs[-1][0] - runs[0][0]:.0f} s from the first to the last, {args.workers} workers")
        print("finished  predicted left  actual left  ratio")
        for n, predicted, actual in replay(runs, args.workers):
            print(f"{n:8d}  {predicted:12.0f} s  {actual:9.0f} s  {predicted / actual if actual else float('nan'):5.2f}")


if __name__ == "__main__":
    main()
