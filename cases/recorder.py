"""What a time-stepping solver records step by step, and the :class:`RunResult` it makes of it.

Bookkeeping shared in shape by the solvers' step loops (no numerics): the probe rows, the
iterations of each step, the field frames every ``every`` steps, the plastic-zone snapshots at
the case's ``plastic_zone_times``, the progress callback, and a failed step's message. The
solver makes the rows, frames and snapshots; the recorder says when they are due::

    recorder = StepRecorder(case, probe_names, every, progress, frame=..., snapshot=...)
    recorder.record(0, row0)
    try:
        for n, row, iterations in steps:
            recorder.record(n, row, iterations)
    except StepFailed as err:
        recorder.fail(str(err))
    return recorder.result(n_dof=..., cpu_time_s=..., mesh=..., info=...)
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from .result import RunResult, ZoneSnapshot


class StepRecorder:
    """Records steps ``0, 1, ..., n`` of a case's window, in order, until one fails.

    Parameters
    ----------
    case : cases.Case (its ``dt``, ``n_steps`` and ``references['plastic_zone_times']``)
    probe_names : the columns of every row, in order
    every : a frame every ``every`` steps, step 0 included (0: none)
    progress : optional ``callable(step, n_steps)``, after every step but step 0
    frame : ``callable()`` -> the field mesh of the step being recorded; called only when due
    snapshot : ``callable(t)`` -> :class:`ZoneSnapshot` of the step being recorded, called only
        at the plastic-zone times (steps >= 1); None: the run makes none (elastic, or a solver
        that cannot draw the zones)
    """

    def __init__(self, case, probe_names, every: int = 0, progress: Callable[[int, int], None] | None = None,
                 frame: Callable[[], object] | None = None,
                 snapshot: Callable[[float], ZoneSnapshot] | None = None):
        self.dt, self.n_steps = case.dt, case.n_steps
        self.names = list(probe_names)
        self.values = np.full((self.n_steps + 1, len(self.names)), np.nan)
        self.every, self.progress, self.frame, self.snapshot = every, progress, frame, snapshot
        times = case.references.get("plastic_zone_times", ()) if snapshot is not None else ()
        self.zone_steps = frozenset(int(round(t / self.dt)) for t in times)
        self.iterations: list[int] = []
        self.frames: list = []
        self.snapshots: list[ZoneSnapshot] = []
        self.message = ""

    def record(self, n: int, row, iterations: int = 0) -> None:
        """Step ``n``'s probe row (``iterations``: of steps >= 1; step 0 is the initial state)."""
        self.values[n] = row
        if self.every and n % self.every == 0:
            self.frames.append((n * self.dt, self.frame()))
        if n == 0:
            return
        self.iterations.append(iterations)
        if n in self.zone_steps:
            self.snapshots.append(self.snapshot(n * self.dt))
        if self.progress is not None:
            self.progress(n, self.n_steps)

    def fail(self, message: str) -> None:
        """The run stops here with ``message`` (the first one stands; an empty one changes nothing)."""
        self.message = self.message or message

    @property
    def done(self) -> int:
        """How many times are recorded, t = 0 included (a failed step is the ``done``-th)."""
        return len(self.iterations) + 1

    @property
    def last_time(self) -> float:
        """The time of the last recorded step, s."""
        return (self.done - 1) * self.dt

    def result(self, **solver_facts) -> RunResult:
        """The run record of the steps recorded; ``solver_facts`` adds ``n_dof``,
        ``cpu_time_s``, ``mesh`` and ``info``."""
        done = self.done
        # n * dt as each solver's march has it: np.arange's integers times dt round alike
        return RunResult(t=np.arange(done) * self.dt,
                         history={name: self.values[:done, j] for j, name in enumerate(self.names)},
                         iterations=self.iterations, converged=not self.message, message=self.message,
                         frames=self.frames, snapshots=self.snapshots, **solver_facts)
