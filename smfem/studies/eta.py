"""How long a study's runs still to come should take: its progress says "about ... left".

A run made before (by any code version: the run cache keeps them) is expected to take what it
took then. Any other is predicted from the runs of this study that have finished:
- those of the same scene and solver give a power law in work (:func:`smfem.studies.ladder.work`:
  elements, steps, harmonics), fitted in logs, its exponent between 0.3 and 1.5; with fewer than
  three of them, or their work within a factor 1.6, the exponent is 0.7 (a small run's fixed
  costs: the 3-D thick cylinder took 2.8 s at work 100 and 99.6 s at 43200);
- else the median wall time of the finished runs of the same solver, else of all;
- with nothing finished yet, the mean of the earlier wall times known, else nothing is said.
The runs share the workers, and no estimate is shorter than the longest run left.

Replayed on finished studies in the order their runs finished (``python benchmarks/time_left.py``):
0.5-2.2 times the time actually left (docs/verification.md). Its blind spot: a solver none of
whose runs has finished yet. The moving load's full study said "about 2 s left" while its one
CalculiX run, counted at the median of the finished runs, had 3 minutes to go.
"""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from smfem.runs.registry import lookup

from .cache import Run, RunCache
from .jobs import Job
from .ladder import work

#: the fitted exponent's bounds; the exponent taken below three runs or this spread in log work
EXPONENT = (0.3, 1.5)
DEFAULT_EXPONENT = 0.7
MIN_LOG_SPREAD = 0.5


def power_law(done: list[tuple[float, float]]) -> tuple[float, float]:
    """``(a, b)`` of the wall time ``exp(a) * work ** b`` fitted to ``done``'s ``(work, wall)``
    pairs (at least one)."""
    x, y = np.log([w for w, _ in done]), np.log([s for _, s in done])
    b = DEFAULT_EXPONENT
    if len(done) >= 3 and np.ptp(x) > MIN_LOG_SPREAD:
        b = float(np.clip(np.polyfit(x, y, 1)[0], *EXPONENT))
    return float(np.mean(y - b * x)), b


class TimeLeft:
    """The runs waiting (``expect``) and finished (``finished``); ``seconds()`` the estimate."""

    def __init__(self, cache: RunCache, workers: int):
        self.cache, self.workers = cache, max(workers, 1)
        self.waiting: dict[Job, tuple[float | None, float]] = {}  # job -> (its earlier wall time or None, its work)
        self.done: dict[tuple, list[tuple[float, float]]] = defaultdict(list)  # (scene, solver) -> (work, wall)
        self.fits: dict[tuple, tuple[float, float]] = {}  # (scene, solver) -> power_law(done), while it holds

    def expect(self, jobs: list[Job]) -> None:
        for job in jobs:
            self.waiting[job] = self.cache.previous_wall(job), _work(job)

    def finished(self, job: Job, run: Run) -> None:
        _, size = self.waiting.pop(job, (None, None))
        wall = (run.summary or {}).get("wall_time_s")
        if wall and wall > 0:
            self.done[_group(job)].append((_work(job) if size is None else size, float(wall)))
            self.fits.pop(_group(job), None)

    def seconds(self) -> float | None:
        """Seconds the waiting runs should take on the workers; None before anything is known."""
        times = [self._expected(job, *known) for job, known in self.waiting.items()]
        if not times:
            return None
        if any(t is None for t in times):
            finished = [(group, wall) for group, runs in self.done.items() for _, wall in runs]
            known = [t for t in times if t is not None]
            if not finished and not known:
                return None
            for i, job in enumerate(self.waiting):
                if times[i] is None:
                    times[i] = _like(job, finished) if finished else sum(known) / len(known)
        return max(sum(times) / self.workers, max(times))

    def _expected(self, job: Job, earlier: float | None, size: float) -> float | None:
        if earlier is not None:
            return earlier
        group = _group(job)
        if group not in self.done:
            return None
        if group not in self.fits:
            self.fits[group] = power_law(self.done[group])
        a, b = self.fits[group]
        return math.exp(a + b * math.log(size))


def _like(job: Job, finished: list[tuple[tuple, float]]) -> float:
    """The median wall time of the ``finished`` runs of ``job``'s solver, else of all."""
    same = [wall for (_, solver), wall in finished if solver == job.solver]
    return float(np.median(same or [wall for _, wall in finished]))


def _group(job: Job) -> tuple:
    return job.case, job.solver


def _work(job: Job) -> float:
    entry = lookup(job.solver)
    return work(job.resolved.params, entry.harmonics, entry.courant)
