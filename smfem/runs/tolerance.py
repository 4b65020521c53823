"""``smfem run CASE --tol 1%``: the cheapest settings expected to reach an accuracy.

Start at the case's settings (for a built-in scene, the caller chooses them from its measured
front: the cheapest run whose error against the truth met the target, whose ``measured``
error then stands for the run's), estimate the run's error (:mod:`smfem.runs.estimate`), and while the
estimate is above the target refine the parts that hold it up: each part above its share of
the target (the target over the number of parts) is refined by the power of two its order
says brings it within the share (refine x 2^k, harmonics x 2^k, dt / 2^k; at most x 4 at a
time, so a pre-asymptotic estimate cannot send the next run far off). Every run and its
estimate are kept; the search stops at the first run whose estimate meets the target, or when
the CPU spent would pass ``max_cpu`` (the best run is then the answer, and the caller says
the target was not met). A run outside the small-strain model (:mod:`smfem.runs.validity`) is
kept as any other, marked: its estimate measures the discretization of a model that does not
hold, and the caller claims no accuracy for it.
"""

from __future__ import annotations

import functools

import math
import time
from dataclasses import dataclass, field

from cases import ParameterError, rebuild
from cases.params import failure

from . import validity
from .estimate import PARTS, estimate, headline
from .registry import solve

#: how much one step of the search may refine a part
MAX_FACTOR = 4


@dataclass
class Attempt:
    case: object
    result: object
    estimate: dict
    error: float  # the largest estimated total over the displacement and velocity probes
    cpu_s: float  # the run's and its companions'
    wall_s: float
    #: the error measured against the truth at these settings (a built-in scene's front), or None
    measured: float | None = None
    valid: bool = True

    @property
    def achieved(self) -> float:
        """The error the run is known to have: measured against the truth where it was, else estimated."""
        return self.error if self.measured is None else self.measured

    @property
    def partial(self) -> bool:
        """Its estimate leaves a part out (:func:`smfem.runs.estimate.estimate`), and no truth measured it."""
        return self.measured is None and bool(self.estimate.get("partial"))

    def meets(self, target: float) -> bool:
        """Whether the run is shown to be within ``target``: a partial estimate shows nothing."""
        return self.achieved <= target and not self.partial


@dataclass
class Search:
    target: float
    attempts: list[Attempt] = field(default_factory=list)
    #: why the search stopped before a run met the target, where it was not the budget
    stopped: str = ""

    @property
    def best(self) -> Attempt:
        return min(self.attempts, key=lambda a: (not a.meets(self.target), a.achieved))

    @property
    def met(self) -> bool:
        return bool(self.attempts) and self.best.meets(self.target)

    @property
    def cpu_s(self) -> float:
        return sum(a.cpu_s for a in self.attempts)


def next_settings(case, est: dict, target: float) -> dict:
    """Overrides for the next run: each part of the headline probe above its share refined by
    the power of two its order asks for (at most :data:`MAX_FACTOR`)."""
    top = headline(case, est)
    row = est["probes"][top[0]]
    parts = {k: row[k] for k in PARTS if k in row}
    share = target / max(len(parts), 1)
    over = {}
    for part, value in parts.items():
        if not value > share:
            continue
        factor = min(MAX_FACTOR, 2 ** math.ceil(math.log2((value / share) ** (1 / row["orders"][part]))))
        factor = max(factor, 2)
        if part == "space":
            over.update(finer_mesh(case, factor))
        elif part == "harmonics":
            over["harmonics"] = case.harmonics * factor
        else:
            over["dt"] = case.dt / factor
    return over


def finer_mesh(case, factor: int) -> dict:
    """Overrides of a mesh ``factor`` times finer: a coarsened mesh's ``coarsen`` divided first."""
    coarsen = case.params.get("coarsen", 1)
    if coarsen == 1:
        return {"refine": case.refine * factor}
    if coarsen >= factor:
        return {"coarsen": coarsen // factor}
    return {"coarsen": 1, "refine": case.refine * factor // coarsen}


def growth(case, over: dict) -> float:
    """How many times dearer a run with the overrides ``over`` is than ``case``'s: unknowns grow
    with the mesh to the power of the section's dimensions (three in a 3-D model), and with the
    harmonics; steps with 1 / dt."""
    dims = 3 if case.params.get("dim") == 3 else 2
    mesh = over.get("refine", case.refine) / case.refine * case.params.get("coarsen", 1) / over.get(
        "coarsen", case.params.get("coarsen", 1))
    return mesh ** dims * over.get("harmonics", case.harmonics) / case.harmonics * case.dt / over.get("dt", case.dt)


def search(case, solver: str, target: float, max_cpu: float, progress=None, max_runs: int = 8,
           fields: bool = False, measured: float | None = None, estimated: bool = True, options=None,
           on_run=None) -> Search:
    """Runs from ``case``'s settings up, until one's estimate (or, for the first, the error
    ``measured`` against the truth at its settings) meets ``target`` (a fraction), the CPU (runs
    and companions) would pass ``max_cpu`` s. Without ``estimated`` (no companions) only the
    first run's ``measured`` error can meet the target. ``options``: the solver's own, for every
    run and companion. ``on_run(case, result, wall_s)`` is called with each run that finishes,
    before its companions start (the caller writes it: nothing after can lose it). A later run
    that fails, or settings past a parameter's range, end the search with the runs made
    (:attr:`Search.stopped` says why); the first run's failure is the caller's, as a plain run's."""
    run = functools.partial(solve, options=options)
    found = Search(target)
    current = case
    while len(found.attempts) < max_runs:
        wall0 = time.perf_counter()
        try:
            result = run(solver, current, progress=progress, fields=fields)
        except Exception as exc:  # noqa: BLE001 - the runs made so far are the user's
            if not found.attempts:
                raise
            found.stopped = f"the run at the next settings failed: {failure(exc)}"
            break
        if not result.converged:
            if found.attempts:
                found.stopped = f"the run at the next settings did not converge: {result.message}"
            break
        if on_run is not None:
            on_run(current, result, time.perf_counter() - wall0)
        est = estimate(current, solver, result, run=run) if estimated else {"method": "none: --estimate off"}
        top = headline(current, est) if "probes" in est else None
        error = top[1] if top else math.inf
        attempt = Attempt(current, result, est, error, float(result.cpu_time_s) +
                          float(est.get("companions_cpu_total_s", 0.0)), time.perf_counter() - wall0,
                          measured if not found.attempts else None, validity.check(current, result)["valid"])
        found.attempts.append(attempt)
        if attempt.meets(target) or top is None:
            break
        over = next_settings(current, est, target)
        if not over:
            if attempt.partial:
                found.stopped = "the estimate is partial and its measured parts are within the target"
            break
        # the next run costs at least the last one times its refinement: stop before passing the budget
        if found.cpu_s + attempt.cpu_s * growth(current, over) > max_cpu:
            break
        try:
            current = rebuild(current, over)
        except ParameterError as exc:
            found.stopped = f"the next settings are outside the parameters' range: {exc}"
            break
    return found
