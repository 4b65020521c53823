"""The timing pass: the runs that decide a report's speed-ups, timed again one at a time.

A study runs two workers side by side on a shared host and times each run once: a speed-up
whose cheap side takes 0.1-1 s then moves by a factor of two from one report to the next. The
pass repeats each decisive run, in the manner of timeit's autorange and pyperf, with no other
run on the machine: one worker process, one run at a time. The pass goes over every scene in
sweeps, and a run's repeats are spread over at least :attr:`TimingRule.sweeps` of them, so its
minimum is taken over the whole pass, not over the minute its scene happened to meet; within a
scene the runs are interleaved (SMFEM, competitor, SMFEM, competitor, ...) so that a drift of
the host hits both sides of a ratio. Each run is repeated until it has
:attr:`TimingRule.repeats` repeats and :attr:`TimingRule.total_s` CPU s in all; a full report's
and a retime's run also until :attr:`TimingRule.settle_s` CPU s and
:attr:`TimingRule.settle_repeats` repeats or :attr:`TimingRule.max_repeats` repeats, and a
second repeat within :attr:`TimingRule.hold` of its minimum (a minimum seen once is luck). On
this project's shared host a short run's repeats scatter over up to twice its least, and only
one in six to ten lies within 5 % of it: a least of three or four repeats then moves by a fifth
from one pass to the next, a least of thirty by a few per cent, and a 4-25 s run's least of
three by as much (a fifth of its repeats within 5 % of it); a run over :attr:`TimingRule.long_s`
is timed once, and once more while the pass stays within :attr:`TimingRule.budget_s`. The CPU
time is the solve's process time as the run measured it in the study (``RunResult.cpu_time_s``,
one BLAS thread); which runs decide the headline is the report's to say (:mod:`reports.timing`).
"""

from __future__ import annotations

import math
import statistics
from dataclasses import dataclass

from smfem.runs import threads
from smfem.runs.progress import Progress
from smfem.runs.registry import Solver, lookup

from .executors import in_worker
from .jobs import Job, solve_job


#: the CPU s a timing pass may spend before it stops timing a long run a second time (the
#: command line's --timing-budget)
BUDGET_S = 600.0


@dataclass(frozen=True)
class TimingRule:
    """When a run has been timed often enough (the defaults are issue 59's)."""

    #: at least this many repeats ...
    repeats: int = 3
    #: ... and at least this much CPU in all, s
    total_s: float = 2.0
    #: ... and (None: not) at least this much CPU in all, s, up to :attr:`max_repeats`: the least of
    #: a short run's repeats settles only over many (40 interleaved repeats of four 0.04-1 s runs on
    #: an idle host, 2026-11-30: 10-17 % of them within 5 % of their least, 28-42 % within 10 %;
    #: two retimes at three or four repeats a run moved single runs' least by up to 39 %) ...
    settle_s: float | None = 30.0
    #: ... and (with :attr:`settle_s`) at least this many repeats up to :attr:`max_repeats`, a run
    #: under :attr:`long_s` too: a dear run's least of three moved by a fifth between two retimes
    #: (the notched strip's 3D reference 18.3 and 22.1 s, SMFEM's quad9 on the notched cylinder 7.6
    #: and 6.1 s at four and five), and only one in five of its repeats lay within 5 % of the
    #: least of both passes (116 repeats of thirteen 4-25 s runs, 2026-11-30) ...
    settle_repeats: int = 10
    #: ... and its minimum must hold: a second repeat within this share of it (a lone fast repeat,
    #: 0.74 of its run's median, moved a speed-up by a third from one pass to the next) ...
    hold: float = 0.05
    #: ... until this many repeats, or (past :attr:`settle_s`) the pass's CPU passes :attr:`budget_s`
    max_repeats: int = 30
    #: a run over this many CPU s is timed once ...
    long_s: float = 60.0
    #: ... and once more while the whole pass's CPU, with that repeat, stays within this, s
    budget_s: float = BUDGET_S
    #: a run's repeats are spread over at least this many sweeps of the pass (over every scene),
    #: the repeats of a sweep going to the worker together: a host that slows for a minute then
    #: raises one sweep's times, not a run's minimum (two passes whose scenes each met their own
    #: minute of the host disagreed by up to 1.6 times; a batch's repeats keep one another's pace,
    #: 49-51 ms ten times in one batch, 33-44 in the next), so a dear run's ten repeats meet ten
    #: moments of the host
    sweeps: int = 10
    #: a run whose study shot took over this many CPU s is not timed again: the shot stands, as
    #: zero repeats (the quick report: its dearest competitor runs, 7 of 43, would take 137 of the
    #: pass's 330 CPU s and bring the report past ten minutes); None: every run is timed
    kept_s: float | None = None
    #: a run whose study shot is over this many times the cheapest shot among the runs that compete
    #: for its headline cost (SMFEM's two elements; one competitor's engines or procedures) is not
    #: timed, as it cannot decide that cost: its shot stands, outside tables/timing.csv (the quick
    #: report: the notched strip's quad9 at 6 times the 4-node element's, 20 CPU s of its pass);
    #: None: every decisive run is timed
    rivals: float | None = None

    def kept(self, study_cpu_s: float) -> bool:
        """Whether a run whose study shot took ``study_cpu_s`` keeps it untimed."""
        return self.kept_s is not None and study_cpu_s > self.kept_s

    @classmethod
    def of(cls, full: bool, budget_s: float = BUDGET_S, retime: bool = False) -> "TimingRule":
        """The rule of a full report (every decisive run that can decide its cost timed) or a
        quick one (runs over 10 s keep their study shot: the cheap side of a ratio, which moved it
        by two, is timed). A retime has no study to pay for and times every run a full pass
        would: a kept shot does not follow the host as the run's SMFEM side does (one stood still
        while the host slowed by a third). Neither times a run over three times its rivals' (a
        full report's earlier pass: 10 of 95 runs, 1170 of its 7830 CPU s a round, the thick
        cylinder's 3D reference at 1 % at 7 times the explicit engine's among them)."""
        if full or retime:
            return cls(budget_s=budget_s, rivals=3.0)
        # nor does a quick one wait for a minimum to hold: on a shared host a third of its runs
        # then went to nine repeats, and the pass to over eight minutes
        return cls(budget_s=budget_s, kept_s=10.0, settle_s=None, max_repeats=cls.repeats, rivals=3.0, sweeps=4)

    def done(self, times: list[float], spent: float) -> bool:
        """Whether a run timed ``times`` (CPU s) needs no more repeats, ``spent`` CPU s into the pass."""
        if not times:
            return False
        if times[0] > self.long_s:
            return len(times) >= 2 or spent + times[0] > self.budget_s
        if len(times) < self.repeats or sum(times) < self.total_s:
            return False
        if len(times) >= self.max_repeats:
            return True
        if self.settle_s is not None and (sum(times) < self.settle_s or len(times) < self.settle_repeats):
            return False
        return self.held(times) or spent > self.budget_s

    def held(self, times: list[float]) -> bool:
        """Whether two of ``times`` lie within :attr:`hold` of their minimum."""
        return sum(t <= min(times) * (1 + self.hold) for t in times) >= 2

    def batch(self, times: list[float], sweep: int) -> int:
        """How many repeats to take in sweep ``sweep`` (from 0) after ``times``: one before the
        run's time is known, then what is still wanted shared among the sweeps left (the repeats
        and CPU s a run needs, then up to :attr:`settle_s` and :attr:`settle_repeats` within
        :attr:`max_repeats`)."""
        if not times:
            return 1
        needed = max(self.repeats - len(times), math.ceil((self.total_s - sum(times)) / min(times)))
        settling = 0 if self.settle_s is None else min(max(math.ceil((self.settle_s - sum(times)) / min(times)),
                                                           self.settle_repeats - len(times)),
                                                       self.max_repeats - len(times))
        return math.ceil(max(needed, settling, 1) / max(self.sweeps - sweep, 1))


@dataclass(frozen=True)
class Timing:
    """One run's repeats, CPU s in the order taken."""

    job: Job
    times: tuple[float, ...]
    #: False: not timed again, ``times`` the study's single shot (:attr:`TimingRule.kept_s`)
    retimed: bool = True

    @property
    def repeats(self) -> int:
        return len(self.times) if self.retimed else 0

    @property
    def cpu_min(self) -> float:
        """The headline's CPU time: noise only ever adds to a run's time."""
        return min(self.times)

    @property
    def cpu_median(self) -> float:
        return statistics.median(self.times)

    @property
    def cpu_max(self) -> float:
        return max(self.times)


def cpu_of(job: Job, solver: Solver, repeats: int = 1) -> list[float]:
    """The solve's CPU s of ``repeats`` more runs of ``job`` (in a worker process: pinned as a study's)."""
    threads.pin()
    return [float(solve_job(job, solver).cpu_time_s) for _ in range(repeats)]


def in_one_worker(job: Job, repeats: int) -> list[float]:
    """:func:`cpu_of` in one of the session's worker processes, waited for: nothing else runs
    meanwhile (the caller starts the pass once the study's runs and side tables are done)."""
    return in_worker(cpu_of, job, lookup(job.solver), repeats, workers=1).result()


def retime(groups: list[list[Job]], rule: TimingRule = TimingRule(), run=in_one_worker,
           progress: bool = True) -> dict[Job, Timing]:
    """Each job of ``groups`` timed by ``run(job, repeats) -> [CPU s]`` until ``rule`` is met.

    ``groups``: one list per scene, in the order to interleave (SMFEM, competitor, SMFEM, ...).
    The pass sweeps over the scenes, each sweep running every job that still needs a repeat
    (:meth:`TimingRule.batch` times), scene by scene in that order: the two sides of a ratio see
    the same host, and a run's repeats the whole pass.
    """
    times: dict[Job, list[float]] = {job: [] for group in groups for job in group}
    spent, sweep = 0.0, 0
    with Progress(len(times), "timing", "run", enabled=progress) as bar:
        while any(not rule.done(t, spent) for t in times.values()):
            for group in groups:
                for job in [job for job in group if not rule.done(times[job], spent)]:
                    cpu = run(job, rule.batch(times[job], sweep))
                    times[job] += cpu
                    spent += sum(cpu)
                    bar.update(sum(rule.done(t, spent) for t in times.values()), f"sweep {sweep + 1}: {job.scene}")
            sweep += 1
    return {job: Timing(job, tuple(t)) for job, t in times.items()}
