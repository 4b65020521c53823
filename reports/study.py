"""The study runner: every run of a plan, from the cache or executed, with a progress bar."""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field

from tqdm import tqdm

from cases import get_case

from .cache import Run, RunCache
from .executors import run_jobs
from .jobs import Job
from .plan import REF3D, SMFEM, CaseStudy


@dataclass
class CaseRuns:
    """The runs of one case study: ``series[solver]`` in level order, and the reference run."""

    study: CaseStudy
    series: dict[str, list[Run]]
    reference: Run
    fields: Run | None

    def all_runs(self) -> list[Run]:
        return [r for runs in self.series.values() for r in runs] + [self.reference]


@dataclass
class StudyResult:
    """Runs per case, and what the build did: runs executed, runs taken from the cache."""

    cases: list[CaseRuns]
    executed: list[Job] = field(default_factory=list)
    cached: int = 0
    wall_time_s: float = 0.0


def _jobs(study: CaseStudy) -> tuple[dict, Job, Job]:
    """Jobs of the series, of the reference run and of the SMFEM run at the case's settings,
    which writes fields.vtu (the series run with those parameters, when there is one)."""
    def params(level):
        return get_case(study.case, {**study.base, **level}).params

    shown = params({})

    def job(solver, level):
        return Job.make(study.case, solver, {**study.base, **level},
                        fields=solver == SMFEM and params(level) == shown)

    series = {s.solver: [job(s.solver, level) for level in s.levels] for s in study.series}
    fields = next((j for j in series.get(SMFEM, ()) if j.fields), None) or job(SMFEM, {})
    return series, job(*study.reference), fields


def _cost_order(job: Job) -> tuple:
    """Longest runs first, so that two workers finish together: 3-D, then finer meshes."""
    o = dict(job.overrides)
    return (job.solver != REF3D, -o.get("refine", 1), -o.get("harmonics", 0))


def run_study(plan: tuple[CaseStudy, ...], cache: RunCache, scheduler: str | None = None, workers: int = 2,
              progress: bool = True) -> StudyResult:
    """Run (or take from ``cache``) every run of ``plan``.

    Parameters
    ----------
    plan : case studies (:mod:`reports.plan`)
    cache : where finished runs are kept
    scheduler : address of a dask.distributed scheduler; None runs on local processes
    workers : local worker processes
    progress : show a progress bar over the runs (on stderr)
    """
    wall0 = time.perf_counter()
    layout = [(study, *_jobs(study)) for study in plan]
    # one run per cache entry: different overrides may resolve to the same parameters
    wanted = {}
    for _, series, ref, fields in layout:
        for job in [*sum(series.values(), []), ref, fields]:
            wanted.setdefault(cache.path(job), job)
    found = {path: run for path, job in wanted.items() if (run := cache.load(job)) is not None}
    missing = sorted((job for path, job in wanted.items() if path not in found), key=_cost_order)
    with tqdm(total=len(missing), desc="study", unit="run", file=sys.stderr, disable=not progress or None) as bar:
        for job, outcome in run_jobs(missing, scheduler, workers):
            found[cache.path(job)] = cache.store(job, outcome)
            bar.set_postfix_str(job.describe(), refresh=False)
            bar.update()
    runs = {job: found[cache.path(job)] for _, series, ref, fields in layout
            for job in [*sum(series.values(), []), ref, fields]}
    cases = [CaseRuns(study, {s: [runs[j] for j in js] for s, js in series.items()}, runs[ref], runs[fields])
             for study, series, ref, fields in layout]
    return StudyResult(cases, executed=missing, cached=len(wanted) - len(missing),
                       wall_time_s=time.perf_counter() - wall0)
