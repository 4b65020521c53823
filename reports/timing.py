"""The report's timing pass: which runs decide its speed-ups, their CPU time as a minimum over
repeats (:mod:`smfem.studies.timing`) in the headline, and ``tables/timing.csv``.

The decisive runs are each solver's cheapest run within each headline target on each scene: the
runs behind the headline's ``cpu_s_to_*`` cells (:func:`smfem.studies.metrics.cost_to`). Their
costs take the minimum of the repeats, so SMFEM's speed-ups, its cheaper element and the
verdict are ratios and choices of minima. The study's own single-shot CPU times stay in
``runs.csv``, ``fronts.csv`` and the work-precision figures; a bound (``> x``: a solver that
does not reach the target) keeps the single shot of that solver's dearest run. A quick pass
times only the decisive runs that can decide their cost (:func:`contenders`): SMFEM's element
whose shot is several times the other's keeps its shot, as its row's cost, outside the pass.
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import asdict, replace
from itertools import zip_longest
from pathlib import Path

import pandas as pd

from smfem.runs.registry import headline_name, lookup
from smfem.studies import provenance
from smfem.studies import timing as studies_timing
from smfem.studies.cache import Run, key_of
from smfem.studies.jobs import OK
from smfem.studies.metrics import REACHED
from smfem.studies.plan import SMFEM
from smfem.studies.timing import Timing, TimingRule, in_one_worker, retime

from .analysis import CaseAnalysis
from .host_gate import HostGate

COLUMNS = ["case", "solver", "target", "label", "repeats", "cpu_min_s", "cpu_median_s", "cpu_max_s", "study_cpu_s"]
#: ``tables/timing_repeats.csv``: every repeat of the pass in the order taken, when its batch ended
REPEAT_COLUMNS = ["case", "solver", "label", "batch", "repeat", "cpu_s", "batch_ended", "host_probe_s", "host_waits"]


def decisive(an: CaseAnalysis) -> dict[tuple[str, float], Run]:
    """``(solver, target) -> run``: the run behind each headline cost that reaches its target."""
    found = {}
    for solver, s in an.solvers.items():
        if s.status != OK:
            continue
        by_label = {run.label: run for run in an.runs.series[solver]}
        found |= {(solver, target): by_label[cost.label] for target, cost in s.costs.items() if cost.how == REACHED}
    return found


def study_shot(run: Run) -> float:
    """The CPU s the study measured for ``run``, once: what a run not timed again keeps."""
    return float(run.summary["cpu_time_s"])


def contenders(runs: dict[tuple[str, float], Run], rivals: float | None) -> dict[tuple[str, float], Run]:
    """``runs`` (:func:`decisive`) less those that cannot decide the cost they compete for: a run
    whose study shot is over ``rivals`` times the cheapest shot at its target among its rivals
    (SMFEM's elements, whose cheaper one is SMFEM's cost; the engines or procedures of one
    headline row). None: all of them."""
    if rivals is None:
        return runs
    shot = {key: study_shot(run) for key, run in runs.items()}

    def rows(solver: str) -> str:
        return SMFEM if lookup(solver).family == SMFEM else headline_name(solver)

    cheapest = {}
    for (solver, target), cpu in shot.items():
        key = (rows(solver), target)
        cheapest[key] = min(cpu, cheapest.get(key, cpu))
    return {(solver, target): run for (solver, target), run in runs.items()
            if shot[solver, target] <= rivals * cheapest[rows(solver), target]}


def interleaved(runs) -> list:
    """The distinct jobs of ``runs`` in the order to time them: SMFEM's and the others' by turns."""
    jobs = list(dict.fromkeys(run.job for run in runs))
    mine = [j for j in jobs if lookup(j.solver).family == SMFEM]
    others = [j for j in jobs if lookup(j.solver).family != SMFEM]
    return [j for pair in zip_longest(mine, others) for j in pair if j is not None]


def boot() -> str:
    """This boot of this machine (Linux's ``boot_id``; '' elsewhere): repeats from another
    machine, or another boot of it, are not this pass's."""
    try:
        return Path("/proc/sys/kernel/random/boot_id").read_text().strip()
    except OSError:
        return ""


class PassLog:
    """The repeats of a timing pass as it takes them, one JSON line per batch in ``path``, so that
    a pass stopped half way (a full report's pass takes hours: its dearest runs are timed once
    each, CalculiX's for over an hour) resumes where it stopped: a resumed pass replays the logged
    batches in the order the pass asks for them, then times the rest. A log is taken up only
    when it was made on this boot of this machine, by the same rule and timing module, from the
    same :data:`~smfem.studies.provenance.SOURCES`; else it is started anew. The pass removes it
    when it finishes (:func:`time_headline`): a later pass, a ``--retime``, times afresh."""

    def __init__(self, path: Path, rule: TimingRule, run=in_one_worker):
        self.path, self.run = Path(path), run
        self.header = {"rule": asdict(rule), "boot": boot(), "commit": provenance.commit(provenance.SOURCES),
                       # the timing module is no run's source (provenance.NOT_IN_A_RUN), but it takes the repeats
                       "timer": hashlib.sha256(Path(studies_timing.__file__).read_bytes()).hexdigest()[:16]}
        self.logged: dict[str, list[dict]] = {}
        #: the pass's batches in the order it asked for them (logged ones replayed among them)
        self.batches: list[dict] = []
        lines = self.path.read_text().splitlines() if self.path.exists() else []
        if lines and self._resumable(json.loads(lines[0])):
            for line in lines[1:]:
                entry = json.loads(line)
                self.logged.setdefault(entry["job"], []).append(entry)
        else:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.path.write_text(json.dumps(self.header) + "\n")

    def _resumable(self, header: dict) -> bool:
        keys = ("rule", "boot", "timer")
        same = {k: header.get(k) for k in keys} == {k: self.header[k] for k in keys}
        return same and bool(header["boot"]) and provenance.same_sources(header.get("commit"))

    @property
    def resumed(self) -> int:
        """How many logged repeats this pass takes up."""
        return sum(len(entry["times"]) for batches in self.logged.values() for entry in batches)

    def __call__(self, job, repeats: int) -> list[float]:
        """``repeats`` CPU times of ``job``: its next logged batch, else measured and logged."""
        key = json.dumps(key_of(job), sort_keys=True, default=str)
        batches = self.logged.get(key)
        if batches:
            entry = batches.pop(0)
        else:
            entry = {"job": key, "times": self.run(job, repeats), "ended": time.strftime("%Y-%m-%d %H:%M:%S UTC",
                                                                                          time.gmtime()),
                     # the host's memory speed before the batch, where the run waits for it (HostGate)
                     "probe_s": getattr(self.run, "last_probe", None), "waits": getattr(self.run, "last_waits", None)}
            with self.path.open("a") as f:
                f.write(json.dumps(entry) + "\n")
        self.batches.append(dict(entry, of=job))
        return entry["times"]

    def repeats(self, label) -> pd.DataFrame:
        """Every repeat taken, in order (:data:`REPEAT_COLUMNS`); ``label(job) -> (case, solver, label)``."""
        rows = [(*label(b["of"]), n, i + 1, t, b.get("ended", ""), b.get("probe_s"), b.get("waits"))
                for n, b in enumerate(self.batches, 1) for i, t in enumerate(b["times"])]
        return pd.DataFrame(rows, columns=REPEAT_COLUMNS)

    def finish(self) -> None:
        self.path.unlink(missing_ok=True)


def time_headline(analyses: list[CaseAnalysis], rule: TimingRule = TimingRule(), progress: bool = True,
                  log: Path | None = None, repeats: Path | None = None, **retime_options) -> pd.DataFrame:
    """Time every scene's decisive runs again and put each minimum in its cost (and the timing in
    ``an.timings``): the headline made after this holds ratios of minima. Returns the rows of
    ``tables/timing.csv``; ``log``: where the pass keeps its repeats until it finishes
    (:class:`PassLog`; each batch then waits for a quiet host, :class:`~reports.host_gate.HostGate`),
    and ``repeats`` where it then writes each of them in the order taken, with when its batch
    ended and the host's memory probe before it (``tables/timing_repeats.csv``: what the host
    did during the pass); ``retime_options``: :func:`smfem.studies.timing.retime`'s ``run``."""
    chosen = {an.case.name: contenders(decisive(an), rule.rivals) for an in analyses}
    timed = [[run for run in runs.values() if not rule.kept(study_shot(run))] for runs in chosen.values()]
    gate = retime_options.get("run") or (HostGate(waits=0) if log is not None else None)
    if isinstance(gate, HostGate):  # a cheap batch need not wait for a quiet host
        gate.expected = {run.job: study_shot(run) for runs in timed for run in runs}
    passlog = PassLog(log, rule, gate) if log is not None else None
    if passlog is not None:
        retime_options["run"] = passlog
        if passlog.resumed and progress:
            print(f"timing: resuming the pass stopped after {passlog.resumed} repeats ({log})", flush=True)
    timings = retime([interleaved(runs) for runs in timed if runs], rule, progress=progress, **retime_options)
    if passlog is not None:
        if repeats is not None:
            named = {run.job: (an.case.name, solver, run.label) for an in analyses
                     for (solver, _), run in chosen[an.case.name].items()}
            passlog.repeats(named.__getitem__).to_csv(repeats, index=False)
        passlog.finish()
    timings |= {run.job: Timing(run.job, (study_shot(run),), retimed=False) for runs in chosen.values()
                for run in runs.values() if rule.kept(study_shot(run))}
    rows = []
    for an in analyses:
        for (solver, target), run in chosen[an.case.name].items():
            timing, costs = timings[run.job], an.solvers[solver].costs
            costs[target] = replace(costs[target], cpu=timing.cpu_min)
            an.timings[solver, target] = timing
            rows.append({"case": an.case.name, "solver": solver, "target": target, "label": run.label,
                         "repeats": timing.repeats, "cpu_min_s": timing.cpu_min, "cpu_median_s": timing.cpu_median,
                         "cpu_max_s": timing.cpu_max, "study_cpu_s": run.summary["cpu_time_s"]})
    return pd.DataFrame(rows, columns=COLUMNS)


def speedup_range(an: CaseAnalysis, solver: str, target: float, cost, smfem_cost) -> str:
    """``'262-301'``: the speed-up over ``solver``'s headline row at ``target`` (``cost``: its
    cost there; a row of one solver's procedures takes the procedure whose cost it is) from the
    repeats' extremes (its slowest SMFEM repeat against the other's fastest, and the other way
    round); '' where either side was not timed (``smfem_cost``: SMFEM's cost there, with its
    cheaper element)."""
    other = next((t for (s, at), t in an.timings.items() if at == target and headline_name(s) == solver
                  and an.solvers[s].costs[at].cpu == cost.cpu), None)
    mine = next((t for (s, at), t in an.timings.items()
                 if at == target and lookup(s).family == SMFEM and an.solvers[s].costs[at] is smfem_cost), None)
    if other is None or mine is None:
        return ""
    return f"{other.cpu_min / mine.cpu_max:.3g}-{other.cpu_max / mine.cpu_min:.3g}"


def timed_runs(timing: pd.DataFrame) -> pd.DataFrame:
    """The rows of ``tables/timing.csv`` one per run timed (a run can decide both targets)."""
    return timing.drop_duplicates(["case", "solver", "label"])
