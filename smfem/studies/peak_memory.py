"""A run's peak memory predicted before it starts, and the rule that keeps the runs started
together within the machine's available memory.

A run made before (by any code version: the run cache keeps them) is expected to peak where it
peaked then (summary.json's ``peak_memory_mb``, :mod:`smfem.runs.memory`). Any other run of a
scene and solver with runs on record is predicted from its unknowns: those of the recorded run
nearest in :func:`~smfem.studies.ladder.size` (cells times harmonics), scaled by the size, times
that solver's bytes per unknown on this scene, from its largest recorded run (a direct
factorization's fill per unknown grows with the mesh, so the largest run's is the closest),
above the smallest run's peak (the worker process's own: Python, numpy, scipy). A run with no
relative on record is not predicted (0 bytes): it starts as before, and the runs after it are
predicted from it. The runs a study finishes join the record as they finish (:meth:`learn`), so
a carried ladder's next level is predicted from the levels below it.
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass
from typing import Callable

from smfem.linalg import available_bytes
from smfem.runs.registry import lookup

from .cache import Run, RunCache
from .jobs import Job
from .ladder import size

MB = 1e6


@dataclass(frozen=True)
class _Recorded:
    size: float
    n_dof: int
    peak_bytes: float


class PeakMemory:
    """``predict(job)``: the job's predicted peak resident memory, bytes, from ``cache``'s record."""

    def __init__(self, cache: RunCache):
        self.cache = cache
        self._relatives: dict[tuple[str, str], list[_Recorded]] | None = None
        self.predicted: dict[Job, float] = {}  # asked at every start, of every job waiting

    @property
    def relatives(self) -> dict[tuple[str, str], list[_Recorded]]:
        """The recorded runs by scene and solver; the cache read when first asked (a study whose
        runs are all cached starts none)."""
        if self._relatives is None:
            self._relatives = defaultdict(list)
            for record in self.cache.earlier().values():
                self._add(record["case"], record["solver"], record["params"], record["n_dof"], record["peak_memory_mb"])
        return self._relatives

    def _add(self, case: str, solver: str, params: dict, n_dof, peak_mb) -> None:
        if n_dof and peak_mb:
            self.relatives[case, solver].append(_Recorded(size(params, lookup(solver).harmonics), int(n_dof),
                                                          float(peak_mb) * MB))

    def learn(self, job: Job, run: Run) -> None:
        """Take a run the study has just finished into the record."""
        s = run.summary or {}
        self._add(job.case, job.solver, job.resolved.params, s.get("n_dof"), s.get("peak_memory_mb"))
        self.predicted = {j: b for j, b in self.predicted.items() if (j.case, j.solver) != (job.case, job.solver)}

    def __call__(self, job: Job) -> float:
        if job not in self.predicted:
            self.predicted[job] = self._predict(job)
        return self.predicted[job]

    def _predict(self, job: Job) -> float:
        earlier = self.cache.previous(job)
        if earlier and earlier.get("peak_memory_mb"):
            return float(earlier["peak_memory_mb"]) * MB
        relatives = self.relatives.get((job.case, job.solver))
        if not relatives:
            return 0.0
        wanted = size(job.resolved.params, lookup(job.solver).harmonics)
        nearest = min(relatives, key=lambda r: abs(math.log(r.size / wanted)))
        largest = max(relatives, key=lambda r: r.n_dof)
        process = min(r.peak_bytes for r in relatives)
        per_unknown = max(largest.peak_bytes - process, 0.0) / largest.n_dof
        return process + nearest.n_dof * wanted / nearest.size * per_unknown


@dataclass(frozen=True)
class MemoryLimit:
    """Runs started together hold at most ``limit`` bytes by ``predict(job)``; a run predicted
    over the limit alone starts only when nothing else runs."""

    predict: Callable[[Job], float]
    limit: float

    @classmethod
    def of_machine(cls, predict: Callable[[Job], float]) -> MemoryLimit:
        """The limit at the machine's available memory now (one reading: the runs it admits
        lower it as they grow)."""
        return cls(predict, float(available_bytes()))

    def pick(self, waiting: list[Job], running: list[Job]) -> Job | None:
        """The first of ``waiting`` that fits beside ``running``, or None."""
        held = sum(self.predict(job) for job in running)
        return next((job for job in waiting if not running or held + self.predict(job) <= self.limit), None)
