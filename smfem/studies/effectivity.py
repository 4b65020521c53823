"""How honest is a run's error estimate? Its effectivity: the estimate (:mod:`smfem.runs.estimate`)
over the run's actual error against the truth, per displacement and velocity probe.

A study estimates each of its ``estimated`` solvers at three settings (:func:`settings`): the
case's defaults, twice its mesh, half its step. The runs and their companions are study jobs
like any other, so they run in parallel and stay in the run cache; the companions an estimate
asks for only after seeing the others (a part measured on the finer side, :func:`asked`) are
asked for as soon as those are in (:class:`Followers`), beside the rest of the study.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pandas as pd

from cases import get_case
from smfem.runs.estimate import PARTS, companions, estimate

from .jobs import OK, Job
from .metrics import TRUTH_MARGIN, history_errors

#: the band an honest estimate keeps to: not below the error, and not so far above it that it
#: says nothing (the error-estimate issue's criterion)
BAND = (0.8, 3.0)


def settings(name: str, base: dict | None = None) -> dict[str, dict]:
    """The settings whose estimates a study of case ``name`` (with its ``base`` overrides)
    measures, as level overrides by label."""
    case = get_case(name, base or {})
    return {"defaults": {}, "refine 2": {"refine": 2 * case.refine}, "dt/2": {"dt": case.dt / 2}}


def planned(study, job_of) -> dict[tuple[str, str], tuple[Job, list[Job]]]:
    """Per (solver, setting): the run's job (``job_of(solver, level)``, the study's own, so that
    a series run is not run twice) and the jobs of its companions known beforehand."""
    out = {}
    for solver in study.estimated:
        for label, level in settings(study.case, study.base).items():
            case = get_case(study.case, {**study.base, **level})
            out[solver, label] = (job_of(solver, level), [
                Job.make(study.case, solver, {**study.base, **level, **c.overrides}) for c in companions(case, solver)])
    return out


def as_result(run):
    """A cached run as :func:`smfem.runs.estimate.estimate` reads a result."""
    ok = run.usable and run.status == OK
    history = {k: run.history[k].to_numpy() for k in run.history.columns if k != "t"} if ok else {}
    return SimpleNamespace(t=run.history["t"].to_numpy() if ok else None, history=history,
                           cpu_time_s=(run.summary or {}).get("cpu_time_s", math.nan), converged=ok,
                           message=run.message or run.status)


def measure(study, plan: dict, fetch) -> dict[tuple[str, str], tuple]:
    """Per (solver, setting): the run and its ``error_estimate``. ``fetch(job)`` gives a job's
    cached run (running it if it is not in the cache)."""
    out = {}
    for (solver, label), (job, _) in plan.items():
        run = fetch(job)
        if not (run.usable and run.status == OK):
            continue
        level = dict(job.overrides)
        case = get_case(study.case, level)

        def companion(solver, c, level=level, case=case):
            changed = {k: v for k, v in c.params.items() if case.params.get(k) != v}
            return as_result(fetch(Job.make(study.case, solver, {**level, **changed})))

        out[solver, label] = (run, estimate(case, solver, as_result(run), run=companion))
    return out


def asked(study, plan: dict, runs: dict) -> list[Job]:
    """The companions the estimates of ``plan`` ask for beyond ``runs`` (a part measured on the
    finer side: known only once its coarser companions are in), so that they too run in
    parallel. Each one asked for is answered with a run at hand; the estimate's arithmetic is
    thrown away."""
    missing, last = [], []

    def fetch(job):
        if job in runs:
            last[:] = [runs[job]]
        elif job not in missing:
            missing.append(job)
        return last[0]
    measure(study, plan, fetch)
    return missing


class Followers:
    """A study's ``follow`` (:func:`smfem.studies.study.run_cached`) for its estimates: once an
    estimate's run and its known companions are all in, the companions it asks for beyond them
    (:func:`asked`), so that they start while the rest of the study runs.

    ``planned``: per study, its :func:`planned` estimates."""

    def __init__(self, planned: list[tuple[object, dict]]):
        self._waiting = [(study, {key: jobs}, {jobs[0], *jobs[1]})
                         for study, plan in planned for key, jobs in plan.items()]
        self._runs: dict = {}

    def __call__(self, job: Job, run) -> list[Job]:
        self._runs[job] = run
        ready, self._waiting = _split(self._waiting, lambda w: w[2] <= self._runs.keys())
        return [j for study, plan, _ in ready for j in asked(study, plan, self._runs)]


def _split(items: list, test) -> tuple[list, list]:
    """``items`` that pass ``test`` and those that do not, each in order."""
    passed = [test(item) for item in items]
    return [i for i, p in zip(items, passed) if p], [i for i, p in zip(items, passed) if not p]


def judged(case, truth, t, history, est: dict) -> list[dict]:
    """One row per displacement or velocity probe of a run (times ``t``, ``history`` by probe)
    and its ``error_estimate``: the estimate and its parts, the actual error against the truth,
    and the effectivity where the truth is fine enough to tell (the actual error above
    :data:`~smfem.studies.metrics.TRUTH_MARGIN` times its uncertainty)."""
    fields = {p.name: p.field for p in case.probes}
    window = case.references.get("comparison_window_s", 0.0)
    out = []
    for probe, parts in ({} if est.get("partial") else est.get("probes", {})).items():  # a partial one is not judged
        if fields.get(probe) not in ("u", "v"):
            continue
        actual = math.nan
        if truth is not None and probe in truth.values and truth.converged(probe):
            actual = history_errors(t, np.asarray(history[probe]), truth.t, truth.values[probe], window)[0]
        fine = math.isfinite(actual) and actual > TRUTH_MARGIN * truth.uncertainty[probe]
        out.append({"probe": probe, "estimate": parts["total"], "actual": actual,
                    "effectivity": parts["total"] / actual if fine and actual > 0 else math.nan,
                    **{f"estimate_{k}": parts[k] for k in PARTS if k in parts},
                    **{f"order_{k}": v for k, v in parts["orders"].items()},
                    "measured_upward": " ".join(est.get("measured_upward", ())),
                    "claim": est.get("claim", ""), "run_cpu_s": est["run_cpu_s"],
                    "companions_cpu_s": est["companions_cpu_total_s"]})
    return out


def rows(case, truth, estimates: dict) -> list[dict]:
    """:func:`judged` for every estimated (solver, setting) of a study's case."""
    return [{"case": case.name, "solver": solver, "setting": label, "level": run.label, **row}
            for (solver, label), (run, est) in estimates.items()
            for row in judged(case, truth, run.history["t"].to_numpy(), run.history, est)]


def summary(table: pd.DataFrame) -> str:
    """One sentence: how many judged probes lie within :data:`BAND`, and the range."""
    judged = table.dropna(subset=["effectivity"]) if len(table) else table
    if not len(judged):
        return "no probe whose truth is fine enough to judge an estimate"
    inside = judged.effectivity.between(*BAND).sum()
    return (f"{inside} of {len(judged)} probe estimates within [{BAND[0]:g}, {BAND[1]:g}] of the actual error "
            f"(effectivity {judged.effectivity.min():.2f} ... {judged.effectivity.max():.2f})")
