"""The study runner: every run of a plan, from the cache or executed, with a progress bar."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

from cases import get_case
from smfem.runs.progress import Progress
from smfem.runs.registry import lookup, split_level

from . import effectivity
from .cache import Run, RunCache
from .eta import TimeLeft
from .executors import run_jobs
from .jobs import Job
from .ladder import Ladder
from .peak_memory import MemoryLimit, PeakMemory
from .plan import SMFEM, CaseStudy
from .stored import find as find_stored
from .truth import Truth, assemble, plan_for
from .truth import jobs as truth_jobs


@dataclass
class CaseRuns:
    """The runs of one case study: ``series[solver]`` in level order, the reference run of the
    same-dt comparison, and the truth (None when the study has no truth plan or a run it needs
    has no history) with its runs by role (none for a stored truth)."""

    study: CaseStudy
    series: dict[str, list[Run]]
    #: None where the study has no same-dt reference (its reference FEM is 3D only and past it)
    reference: Run | None
    fields: Run | None
    truth: Truth | None = None
    truth_runs: dict = field(default_factory=dict)
    #: (solver, setting) -> (run, its error_estimate): :mod:`smfem.studies.effectivity`
    estimates: dict = field(default_factory=dict)
    #: solver -> where its carried series stopped and why (:mod:`smfem.studies.ladder`)
    carried: dict = field(default_factory=dict)

    def all_runs(self) -> list[Run]:
        """Every stored run the case read: its series, the same-dt reference, the fields run,
        the truth's runs and the error estimates' runs."""
        return [*(r for runs in self.series.values() for r in runs),
                *(r for r in (self.reference, self.fields) if r is not None), *self.truth_runs.values(),
                *(run for run, _ in self.estimates.values() if run is not None)]


@dataclass
class StudyResult:
    """Runs per case, and what the build did: runs executed, runs taken from the cache."""

    cases: list[CaseRuns]
    executed: list[Job] = field(default_factory=list)
    cached: int = 0
    wall_time_s: float = 0.0


def stored_truth(study: CaseStudy) -> tuple[Truth | None, str]:
    """The stored truth (``smfem/truths/CASE``) of the study's case as the study sets it up, if its
    key matches (:mod:`smfem.studies.stored`), and why not otherwise."""
    if study.truth is None:
        return None, "the study has no truth plan"
    case = get_case(study.case, study.base)
    if case.source is not None:
        return None, "a scene from a file has no stored truth"
    return find_stored(study.case, case, plan_for(study.case, study.base, "full"))


def job_of(study: CaseStudy):
    """``job(solver, level, options=())``: the study's job of a level (with its series' solver
    options, and the level's own: CalculiX's ``modes``, :func:`smfem.runs.registry.split_level`).
    The SMFEM run at the case's own settings writes fields.vtu, whichever level resolves to them."""
    def params(level):
        return get_case(study.case, {**study.base, **level}).params

    shown = params({})

    def job(solver, level, options=()):
        overrides, own = split_level(solver, level)
        options = dict(options) | own
        return Job.make(study.case, solver, {**study.base, **overrides}, options=options,
                        fields=solver == SMFEM and params(overrides) == shown and not options)
    return job


def _jobs(study: CaseStudy, stored: bool, ladders: dict | None = None) -> tuple[dict, Job, Job, dict]:
    """Jobs of the series (a carried one's: its first level; ``ladders`` by solver), of the
    reference run, of the SMFEM run at the case's settings, which writes fields.vtu (the series
    run with those parameters, when there is one), and of the truth by role (none when a
    ``stored`` truth stands in)."""
    job, ladders = job_of(study), ladders or {}
    series = {s.solver: ladders[s.solver].running if s.solver in ladders else
              [job(s.solver, level, s.options) for level in s.levels] for s in study.series}
    fields = next((j for j in series.get(SMFEM, ()) if j.fields), None) or job(SMFEM, {})
    truth = truth_jobs(study.case, study.truth, study.base) if study.truth and not stored else {}
    return series, job(*study.reference) if study.reference else None, fields, truth


def _ladders(study: CaseStudy, truth: Truth | None) -> dict[str, Ladder]:
    """The study's carried series by solver (none without a stored ``truth`` to judge them)."""
    if truth is None:
        return {}
    return {s.solver: Ladder.make(s, study.case, study.base, truth, job_of(study)) for s in study.series if s.until}


def _cost_order(job: Job) -> tuple:
    """Longest runs first, so that two workers finish together: the dear solvers' (3-D, an
    external program), then finer meshes."""
    o = dict(job.overrides)
    return (not lookup(job.solver).dear, -o.get("refine", 1), -o.get("harmonics", 0))


class NotInCache(LookupError):
    """A study asked to run nothing (``smfem report --retime``) lacks runs in its cache."""


def run_cached(jobs: list[Job], cache: RunCache, scheduler: str | None = None, workers: int = 2,
               progress: bool = True, follow=None, cached_only: bool = False) -> tuple[dict, list[Job], int]:
    """Every run of ``jobs``, from ``cache`` or executed (longest first) and stored there, and
    of the jobs that ``follow(job, run) -> [Job]`` asks for once a run is there (the next
    level of a carried series, :mod:`smfem.studies.ladder`: cached, it is read at once; else it runs
    as soon as a worker is free).

    Returns the runs by job (followed ones too), the jobs executed and how many runs came from
    the cache. ``cached_only``: execute nothing; a run missing from the cache raises
    :class:`NotInCache`. Local workers never start runs together whose predicted peak memory
    (:mod:`smfem.studies.peak_memory`) passes the machine's available memory.
    """
    follow = follow or (lambda job, run: [])
    found: dict = {}  # cache path -> run
    waiting: dict = {}  # cache path -> the jobs asked for it (different overrides may resolve alike)
    asked: list[Job] = []
    cached = 0

    def ask(new: list[Job]) -> list[Job]:
        """The jobs of ``new`` (and of what their cached runs ask for) to execute."""
        nonlocal cached
        todo, stack = [], list(new)
        while stack:
            job = stack.pop(0)
            path = cache.path(job)
            asked.append(job)
            if path in found:
                stack += follow(job, found[path])
            elif path in waiting:
                waiting[path].append(job)
            elif (run := cache.load(job)) is not None:
                found[path], cached = run, cached + 1
                stack += follow(job, run)
            else:
                waiting[path] = [job]
                todo.append(job)
        return todo

    queue = sorted(ask(jobs), key=_cost_order)
    if cached_only and queue:
        raise NotInCache(f"{len(queue)} runs of this plan are not in the run cache {cache.root} (the first: "
                         f"{queue[0].describe()}): make the report first, with the same scenes and settings")
    left = TimeLeft(cache, workers)
    if progress:
        left.expect(queue)
    peaks = PeakMemory(cache)
    with Progress(len(queue), "study", "run", enabled=progress) as bar:
        for done, (job, outcome) in enumerate(run_jobs(queue, scheduler, workers, MemoryLimit.of_machine(peaks)),
                                              start=1):
            path = cache.path(job)
            found[path] = cache.store(job, outcome)
            peaks.learn(job, found[path])
            more = ask([j for waiter in waiting.pop(path) for j in follow(waiter, found[path])])
            queue += more
            if progress:
                left.finished(job, found[path])
                left.expect(more)
            bar.grow(len(more))
            bar.update(done, job.describe(), left.seconds() if progress else None)
    return {job: found[cache.path(job)] for job in asked}, queue, cached


def run_study(plan: tuple[CaseStudy, ...], cache: RunCache, scheduler: str | None = None, workers: int = 2,
              progress: bool = True, cached_only: bool = False) -> StudyResult:
    """Run (or take from ``cache``) every run of ``plan``, and assemble each case's truth.

    Parameters
    ----------
    plan : case studies (:mod:`smfem.studies.plan`)
    cache : where finished runs are kept
    scheduler : address of a dask.distributed scheduler; None runs on local processes
    workers : local worker processes
    progress : show a progress bar over the runs (on stderr)
    cached_only : run nothing: every run from the cache, else :class:`NotInCache`
    """
    wall0 = time.perf_counter()
    stored = {study.case: stored_truth(study) for study in plan}
    ladders = {study.case: _ladders(study, stored[study.case][0]) for study in plan}
    by_job = {j: ladder for case in ladders.values() for ladder in case.values() for j in ladder.jobs}
    layout = [(study, *_jobs(study, stored[study.case][0] is not None, ladders[study.case])) for study in plan]
    estimated = {study.case: effectivity.planned(study, job_of(study)) for study in plan}
    every = [job for _, series, ref, fields, truth in layout
             for job in [*sum(series.values(), []), ref, fields, *truth.values()] if job is not None]
    every += [j for jobs in estimated.values() for run, comps in jobs.values() for j in [run, *comps]]
    estimates = effectivity.Followers([(study, estimated[study.case]) for study in plan])

    def follow(job, run):  # a carried series' next level; the companions an estimate asks for
        return (by_job[job].after(job, run) if job in by_job else []) + estimates(job, run)
    runs, executed, cached = run_cached(every, cache, scheduler, workers, progress, follow=follow,
                                        cached_only=cached_only)
    cases = []
    for study, series, ref, fields, truth in layout:
        series |= {solver: ladder.running for solver, ladder in ladders[study.case].items()}
        truth_runs = {role: runs[j] for role, j in truth.items()}
        made, why = stored[study.case]
        if made is None and study.truth:
            made = assemble(study.case, study.truth, study.base, truth_runs)
            if made is not None:
                made.source = f"computed by this study ({why})"
        cases.append(CaseRuns(study, {s: [runs[j] for j in js] for s, js in series.items()},
                              runs[ref] if ref is not None else None, runs[fields],
                              made, truth_runs, effectivity.measure(study, estimated[study.case], runs.__getitem__),
                              {solver: f"{ladder.series.until.describe()}: {ladder.outcome}"
                               for solver, ladder in ladders[study.case].items()}))
    return StudyResult(cases, executed=executed, cached=cached, wall_time_s=time.perf_counter() - wall0)
