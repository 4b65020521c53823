"""Series carried to a target: a series with ``until`` (:class:`smfem.studies.plan.Until`) runs its
levels one after another, cheapest first (by :func:`work`), and stops at its first run whose total error against
the stored truth is at most the target, or before a level whose CPU time, predicted from the
last run's, would pass the budget. Different series still run side by side.

A series is carried only against a stored truth (``smfem/truths/CASE``): a truth the study computes
is there only once every run has finished, so such a series runs all its levels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from cases import get_case
from smfem.runs.registry import lookup, split_level, with_fixed

from . import metrics
from .cache import Run
from .jobs import Job
from .plan import Series


#: the 3D reference's elements round a ring at refine 1 (``reference_fem.mesh.N_THETA``; the
#: studies read the solvers' parameters, not their numerics: a test holds the two equal)
THETA_PER_REFINE = 64


def size(params: dict, per_harmonic: bool) -> float:
    """What a run's unknowns grow with, in the case's parameters: the section's (or body's)
    elements, ``refine ** dim`` over ``coarsen ** dim`` (in 3D the ring's count from
    ``theta_elements`` where set, halved for a ``mirror`` half), and for a harmonic solver the
    harmonics."""
    dim = params.get("dim", 2)
    scale = params.get("refine", 1) / params.get("coarsen", 1)
    cells = scale ** dim
    if dim == 3 and params.get("theta_elements"):
        cells = scale ** 2 * params["theta_elements"] / THETA_PER_REFINE
    if dim == 3 and params.get("mirror"):
        cells /= 2
    return cells * (max(params.get("harmonics", 1), 1) if per_harmonic else 1)


def work(params: dict, per_harmonic: bool, courant: bool = False) -> float:
    """What a run's CPU time grows with, in the case's parameters: its :func:`size` times the
    steps, ``t_end / dt``, and the square of a modal run's ``modes`` (ccx's eigen-solve grows
    about so: benchmarks/README.md; a solver option, passed in ``params`` beside the case's);
    ``courant``: the solver steps at its own Courant limit (:attr:`smfem.runs.registry.Solver.courant`),
    whose steps grow as ``refine`` over ``coarsen`` (``dt`` is its output interval only).
    An estimate for predicting a ladder's next run from its last (direct solvers grow faster
    than this with a 3-D mesh, a plastic run with its iterations)."""
    steps = params["t_end"] / params["dt"] * (params.get("refine", 1) / params.get("coarsen", 1) if courant else 1)
    return size(params, per_harmonic) * params.get("modes", 1) ** 2 * steps


@dataclass
class Ladder:
    """One carried series in a study: its jobs by level, how far it went and why it stopped."""

    series: Series
    case: object
    truth: object
    jobs: list[Job]
    params: list[dict]
    asked: int = 1
    #: why the ladder stopped: '' while it runs; a sentence once it has
    outcome: str = ""

    @classmethod
    def make(cls, series: Series, name: str, base: dict, truth, job) -> Ladder:
        """The ladder of ``series``: its levels in the order of their predicted work
        (:func:`work`; the plan's order among equals). ``job(solver, level, options)``: the
        study's job of a level (:func:`smfem.studies.study.job_of`)."""
        entry = lookup(series.solver)
        split = [split_level(series.solver, level) for level in series.levels]
        params = [with_fixed(series.solver, get_case(name, {**base, **overrides})).params | own
                  for overrides, own in split]
        order = sorted(range(len(params)), key=lambda i: work(params[i], entry.harmonics, entry.courant))
        return cls(series, get_case(name, base), truth,
                   [job(series.solver, series.levels[i], series.options) for i in order], [params[i] for i in order])

    @property
    def running(self) -> list[Job]:
        """The jobs asked so far, in level order."""
        return self.jobs[:self.asked]

    def after(self, job: Job, run: Run) -> list[Job]:
        """The next job once ``run`` (of ``job``) has finished: none when it is not the
        ladder's last asked level, when it reaches the target, when the ladder ends or when the
        next level's predicted CPU time passes the budget (each said in :attr:`outcome`)."""
        i = self.asked - 1
        if self.outcome or job != self.jobs[i]:
            return []
        until = self.series.until
        error = (metrics.headline_error(self.case, self.truth, run.history["t"].to_numpy(), run.history)
                 if run.usable else math.nan)
        cpu = run.summary.get("cpu_time_s", math.nan) if run.summary else math.nan
        if error <= until.target:
            self.outcome = f"reached {100 * until.target:g} % at {run.label} ({100 * error:.3g} %, {cpu:.3g} CPU s)"
            return []
        if self.asked == len(self.jobs):
            self.outcome = f"ladder ended at {run.label} ({_percent(error)}): not reached"
            return []
        entry = lookup(self.series.solver)
        predicted = (cpu * work(self.params[i + 1], entry.harmonics, entry.courant)
                     / work(self.params[i], entry.harmonics, entry.courant))
        if predicted > until.budget_s:
            label = self.jobs[i + 1].describe()
            self.outcome = (f"stopped at {run.label} ({_percent(error)}): the next level ({label}) would take about "
                            f"{predicted:.3g} CPU s, over the budget of {until.budget_s:g} s")
            return []
        self.asked += 1
        return [self.jobs[i + 1]]


def _percent(error: float) -> str:
    return f"{100 * error:.3g} %" if math.isfinite(error) else "no error: the run failed"
