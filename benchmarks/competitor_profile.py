"""Where each competitor's CPU goes at its cheapest run within 1 % (3 % on the notched cylinder):
set-up, solves, the rest of the march, output.

    python benchmarks/competitor_profile.py [--tables DIR] [--scenes NAME ...] [--solvers NAME ...]
                                            [--budget S] [--tiny]

The runs come from a report's tables (``--tables``, default ``docs/full-report/tables``, the
latest full study): per scene and competitor (a row of the headline: the 2D and 3D reference,
the explicit 3D engine where the study has its series, CalculiX at its cheapest procedure) the
cheapest run of ``fronts.csv`` whose total error is within the scene's target
(:func:`smfem.studies.metrics.cost_to` and :func:`~smfem.studies.metrics.cheapest`, against the
truth's uncertainty of ``headline.csv``), else within 5 %; its settings are the study plan's
level of that label. ``--budget``: a run whose study CPU passed it is listed, not run.

Each run is made again as the study made it (:func:`smfem.studies.jobs.solve_job`), its CPU
time split as it goes by timers around the reference's parts (no profiler: a handful of calls
a step, so the parts sum to the run's CPU and cost it nothing); a run whose study CPU is under
a minute is first made for two steps, untimed (the imports and caches that a study's worker has
warm after its first run):

- set-up: the mesh, the model (basis, mass, loads, supports), the system (stiffness, ``K + a0
  M``; a contact system's rows), the probes, the initial acceleration (implicit: ``M a0 = Q``),
  the critical step (explicit: the largest eigenvalue);
- solves: factorizations of ``K + a0 M`` and of tangents, triangular solves, CG on tangents;
- other march: the rest of the step loop (Newmark's update, internal forces, the law, loads);
- output: the probes each step, the recorder, the final mesh and stresses.

CalculiX is timed from outside: writing the deck, ccx's CPU and reading its ``.frd``. ccx
prints no split of its own, so its set-up is estimated from a second run of two output intervals
(its CPU less two intervals' share of the full run's march; ccx's explicit procedure takes no
window of one: its time points then read as an error; the modal procedure's eigen-solve
is its set-up); the factorizations are counted from its log (``Factoring``): the implicit
procedure's two an increment, ccx 2.20's design. The 25 % limit is the reference's alone.

Timings are CPU seconds of one run each, one thread; shares are what compare across machines.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import tempfile
import time
from collections import defaultdict
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from functools import wraps
from pathlib import Path
from unittest import mock

from smfem.runs.threads import pin

pin()

import pandas as pd  # noqa: E402

from cases import get_case  # noqa: E402
from smfem.runs.registry import CALCULIX, SMFEM, headline_name, lookup  # noqa: E402
from smfem.studies import metrics  # noqa: E402
from smfem.studies.cache import Run  # noqa: E402
from smfem.studies.jobs import Job, solve_job  # noqa: E402
from smfem.studies.plan import full, quick  # noqa: E402
from smfem.studies.study import job_of  # noqa: E402

TABLES = Path(__file__).resolve().parents[1] / "docs" / "full-report" / "tables"
#: the targets tried in turn per scene (the first a run reaches is profiled)
TARGETS = {"notched_cylinder": (0.03, 0.05)}
DEFAULT_TARGETS = (0.01, 0.05)
#: the reference's set-up, at most this share of each run (issue 58)
SETUP_LIMIT = 0.25
GROUPS = ("set-up", "solves", "march", "output")


# -- which runs -------------------------------------------------------------------------------
@dataclass(frozen=True)
class Pick:
    """A competitor's cheapest run within a target in a report's tables (``level``: its label;
    ``job``: the plan's job of that label, None where the plan has it no more)."""

    case: str
    competitor: str
    solver: str
    level: str
    target: float
    error: float
    study_cpu: float
    job: Job | None = None
    best: float = math.nan  # where no target is reached: the smallest error

    @property
    def reached(self) -> bool:
        return bool(self.level)


def competitors(solvers) -> dict[str, list[str]]:
    """The headline's competitor rows (not SMFEM's) and their series: CalculiX's procedures
    share one row (:func:`smfem.runs.registry.headline_name`); solvers the table does not know
    (a report's older names) are left out."""
    out = defaultdict(list)
    for solver in solvers:
        try:
            entry = lookup(solver)
        except ValueError:
            continue
        if entry.family != SMFEM:
            out[headline_name(solver)].append(solver)
    return dict(out)


def picks(tables: Path, scenes=(), solvers=()) -> list[Pick]:
    """Per scene (of ``scenes``, all when empty) and competitor (of ``solvers``: a headline row's
    name or one of its series'), the cheapest run of ``tables/fronts.csv`` within the scene's
    first reached target."""
    fronts = pd.read_csv(tables / "fronts.csv")
    headline = tables / "headline.csv"
    uncertainty = {}
    if headline.exists():
        h = pd.read_csv(headline)
        uncertainty = {c: float(u) / 100 for c, u in zip(h.case, h.truth_uncertainty_pct) if u == u}
    out = []
    for case in dict.fromkeys(fronts.case):
        if scenes and case not in scenes:
            continue
        rows = fronts[fronts.case == case]
        for competitor, series in competitors(dict.fromkeys(rows.solver)).items():
            if solvers and competitor not in solvers and not set(series) & set(solvers):
                continue
            runs = rows[rows.solver.isin(series)]
            for target in TARGETS.get(case, DEFAULT_TARGETS):
                costs = [metrics.cost_to(target, r.cpu_s.tolist(), r.total.tolist(),
                                         list(zip(r.solver, r.level)), uncertainty.get(case, 0.0))
                         for _, r in runs.groupby("solver", sort=False)]
                best = metrics.cheapest(costs)
                if best.how == metrics.REACHED:
                    break
            if best.how != metrics.REACHED:
                out.append(Pick(case, competitor, "", "", target, math.nan, math.nan, best=best.best))
                continue
            solver, level = best.label
            error = float(runs[(runs.solver == solver) & (runs.level == level)].total.iloc[0])
            out.append(Pick(case, competitor, solver, level, target, error, best.cpu, job_for(case, solver, level)))
    return out


def job_for(case: str, solver: str, level: str) -> Job | None:
    """The job of the study plan (full, else quick) whose run has the label ``level``."""
    for plan in (full, quick):
        study = next((s for s in plan() if s.case == case), None)
        if study is None:
            continue
        make = job_of(study)
        for series in (s for s in study.series if s.solver == solver):
            for settings in series.levels:
                job = make(solver, settings, series.options)
                if Run(job, "", "", None).label == level:
                    return job
    return None


# -- the split ----------------------------------------------------------------------------------
class Phases:
    """CPU seconds by part of a run, as it goes. A part is ``'group/name'``; time goes to the
    innermost part entered (the step matrix factorized while the contact system is set up is a
    solve), except inside a part that keeps what it calls: solves, output, and the initial
    acceleration (its mass factorization is set-up). Between parts, time goes to the phase:
    set-up until the march starts, the march while it runs, output after it."""

    STICKY = ("solves/", "output/", "set-up/initial acceleration")

    def __init__(self):
        self.seconds = defaultdict(float)
        self.stack = ["set-up/other"]
        self.clock = time.process_time()

    def _charge(self) -> None:
        now = time.process_time()
        self.seconds[self.stack[-1]] += now - self.clock
        self.clock = now

    def enter(self, part: str) -> None:
        self._charge()
        top = self.stack[-1]
        self.stack.append(top if top.startswith(self.STICKY) and len(self.stack) > 1 else part)

    def leave(self) -> None:
        self._charge()
        self.stack.pop()

    def phase(self, part: str) -> None:
        self._charge()
        self.stack[0] = part

    def stop(self) -> dict[str, float]:
        self._charge()
        return dict(self.seconds)

    def timed(self, part: str, f):
        """``f`` charged to ``part``."""
        @wraps(f)
        def wrapper(*args, **kwargs):
            self.enter(part)
            try:
                return f(*args, **kwargs)
            finally:
                self.leave()
        return wrapper

    def marched(self, march):
        """A step generator whose steps are charged to the march (the first step's set-up
        parts to set-up), the phase the march until it ends, output after."""
        @wraps(march)
        def wrapper(*args, **kwargs):
            steps = march(*args, **kwargs)
            self.phase("march/other")
            while True:
                self.enter("march/other")
                try:
                    step = next(steps)
                except StopIteration:
                    break
                finally:
                    self.leave()
                yield step
            self.phase("output/other")
        return wrapper

    def factorized(self, factorize):
        """``factorize`` charged to solves, and the solves with its factors too."""
        phases = self

        class Factors:
            def __init__(self, lu):
                self.lu = lu

            def solve(self, *args, **kwargs):
                return phases.timed("solves/triangular", self.lu.solve)(*args, **kwargs)

            def __getattr__(self, name):
                return getattr(self.lu, name)

        return self.timed("solves/factorization", lambda *a, **k: Factors(factorize(*a, **k)))


@contextmanager
def instrumented(phases: Phases):
    """The reference's parts (implicit and explicit engines) timed by ``phases`` while open."""
    from cases.recorder import StepRecorder
    from reference_fem import equilibrium, explicit, linalg, newmark, pairs, solver, wall
    from reference_fem.model import Model
    from reference_fem.probes import Probes

    patches = [
        (solver, "build_mesh", "set-up/mesh"), (explicit, "build_mesh", "set-up/mesh"),
        (Model, "__init__", "set-up/model"), (solver, "_system", "set-up/system"),
        (explicit.ExplicitSystem, "__init__", "set-up/system"), (Probes, "__init__", "set-up/probes"),
        (newmark, "initial_acceleration", "set-up/initial acceleration"),
        (explicit, "largest_frequency", "set-up/critical step"),
        (linalg.PreconditionedTangent, "solve", "solves/cg"),
        (Probes, "values", "output/probes"), (StepRecorder, "record", "output/recorder"),
        (StepRecorder, "result", "output/recorder"), (wall.ContactLog, "record", "output/contact log"),
        (pairs.PairLog, "record", "output/contact log"),
        (solver, "output_mesh", "output/mesh"), (solver, "error_l2", "output/exact error"),
    ]
    with ExitStack() as stack:
        for owner, name, part in patches:
            original = owner.__dict__[name] if isinstance(owner, type) else getattr(owner, name)
            stack.enter_context(mock.patch.object(owner, name, phases.timed(part, original)))
        for owner in (solver, explicit):
            stack.enter_context(mock.patch.object(owner, "march", phases.marched(owner.march)))
        for owner in (equilibrium, linalg):
            stack.enter_context(mock.patch.object(owner, "factorize", phases.factorized(owner.factorize)))
        yield phases


@dataclass
class Profile:
    """One run's CPU by part (``parts``: ``'group/name'`` -> s), its own ``cpu_time_s`` (what
    the study counts) and what the table notes."""

    parts: dict
    counted: float
    notes: list = field(default_factory=list)

    @property
    def total(self) -> float:
        return sum(self.parts.values())

    def group(self, name: str) -> float:
        return sum(s for part, s in self.parts.items() if part.split("/")[0] == name)


#: runs whose study CPU is below this are first made for two steps, untimed: the imports and
#: caches a study's worker has warm after its first run
WARM_BELOW_S = 60.0


def shortened(job: Job, steps: int) -> Job:
    """``job`` over its first ``steps`` steps."""
    return Job.make(job.case, job.solver, dict(job.overrides) | {"t_end": steps * job.build().dt},
                    options=dict(job.options))


def profile_reference(job: Job) -> Profile:
    """``job`` run by its reference engine as the study runs it, split by :class:`Phases`."""
    phases = Phases()
    with instrumented(phases):
        phases.clock = time.process_time()
        result = solve_job(job, lookup(job.solver))
        parts = phases.stop()
    info, notes = result.info, []
    if "factorizations" in info:
        notes.append(f"{info['factorizations']} factorization(s)")
    if info.get("cg_iterations"):
        notes.append(f"{info['cg_iterations']} CG iterations")
    if "steps" in info:
        notes.append(f"{info['steps']} explicit steps")
    return Profile(parts, result.cpu_time_s, notes)


#: output intervals of the run whose CPU, less their share of the whole run's, is ccx's set-up
SHORT = 2


def profile_calculix(job: Job) -> Profile:
    """``job`` in ccx: the deck written, ccx's CPU, its results read; ccx's own set-up estimated
    from a run of :data:`SHORT` output intervals (module doc)."""
    from reference_fem.calculix.deck import build_deck
    from reference_fem.calculix.solver import find_ccx, read_results, run
    from smfem.runs.registry import with_fixed

    entry = lookup(job.solver)
    options = dict(job.options) | entry.fixed_options
    ccx = find_ccx()

    def ccx_run(case):
        with tempfile.TemporaryDirectory(prefix="smfem-profile-") as tmp:
            work = Path(tmp)
            t0 = time.process_time()
            deck = build_deck(case, procedure=options.get("procedure", "implicit"), modes=options.get("modes"),
                              fields=False)
            (work / "job.inp").write_text(deck.text)
            t1 = time.process_time()
            cpu, log = run(ccx, work, case)
            t2 = time.process_time()
            result = read_results(case, deck, work, log)
            return t1 - t0, cpu, time.process_time() - t2, log, result

    case = with_fixed(entry, job.build())
    deck, cpu, read, log, result = ccx_run(case)
    n = case.n_steps
    setup = cpu
    if n > SHORT:
        _, cpu_short, _, _, _ = ccx_run(with_fixed(entry, get_case(job.case, dict(job.overrides)
                                                                   | {"t_end": SHORT * case.dt})))
        setup = min(max(cpu_short - SHORT * (cpu - cpu_short) / (n - SHORT), 0.0), cpu)
    parts = {"set-up/deck": deck, "set-up/ccx": setup, "march/ccx": cpu - setup, "output/read .frd": read}
    procedure = result.info["procedure"]
    notes = [f"ccx {procedure}" + (f", {result.info['modes']} modes (the eigen-solve is its set-up)"
                                   if procedure == "modal" else f", {result.info['increments']} increments"
                                   if result.info["increments"] else "")]
    factorizations = len(re.findall(r"Factoring the system", log))
    if factorizations:
        notes.append(f"{factorizations} factorizations" + (" (ccx 2.20's *DYNAMIC: at least two iterations, each "
                                                           "assembled and factorized, per increment)"
                                                           if procedure == "implicit" else ""))
    return Profile(parts, cpu, notes)


def profile(job: Job) -> Profile:
    return (profile_calculix if lookup(job.solver).family == CALCULIX else profile_reference)(job)


# -- the table ----------------------------------------------------------------------------------
def command(pick: Pick) -> str:
    return f"python benchmarks/competitor_profile.py --scenes {pick.case} --solvers {pick.solver}"


def row(pick: Pick, budget: float, tiny: bool = False) -> str:
    head = f"| {pick.case} | {pick.competitor} |"
    if not pick.reached:
        return f"{head} not reached (best {100 * pick.best:.2g} %) | {100 * pick.target:g} % |" + " |" * 9
    head += f" {pick.solver} {pick.level} | {100 * pick.target:g} % | {100 * pick.error:.2f} | {pick.study_cpu:.3g} |"
    if pick.job is None:
        return f"{head} | | | | | | not in today's plan: not run |"
    if pick.study_cpu > budget:
        return f"{head} | | | | | | not run: over --budget {budget:g} s (`{command(pick)}`) |"
    job = shortened(pick.job, 4) if tiny else pick.job  # tiny: a check that the script works
    ccx = lookup(job.solver).family == CALCULIX  # timed from outside: its solves are within its march
    if pick.study_cpu < WARM_BELOW_S and not ccx:
        solve_job(shortened(job, 2), lookup(job.solver))
    p = profile(job)
    share = p.group("set-up") / p.total
    setup = ", ".join(f"{part.split('/')[1]} {s:.2f}" for part, s in sorted(p.parts.items(), key=lambda x: -x[1])
                      if part.startswith("set-up") and s >= 0.005)
    flag = " **over 25 %**" if share > SETUP_LIMIT and not ccx else ""  # a limit of the reference's
    return (f"{head} {p.total:.3g} ({p.counted:.3g}) | "
            + " | ".join("-" if ccx and g == "solves" else f"{p.group(g):.3g}" for g in GROUPS)
            + f" | {100 * share:.0f} %{flag} | set-up: {setup}; {'; '.join(p.notes)} |")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tables", type=Path, default=TABLES, help="a report's tables directory (fronts.csv)")
    parser.add_argument("--scenes", nargs="*", default=[])
    parser.add_argument("--solvers", nargs="*", default=[], help="competitors (reference-3d, calculix, ...) or series")
    parser.add_argument("--budget", type=float, default=math.inf, help="skip runs whose study CPU passed it, s")
    parser.add_argument("--tiny", action="store_true", help="the dome's 2D reference, four steps")
    args = parser.parse_args(argv)
    if args.tiny:
        args.scenes, args.solvers = args.scenes or ["dome"], args.solvers or ["reference-2d"]
    print(f"tables: {args.tables}; load average {os.getloadavg()[0]:.1f} (CPU seconds of one run each, one thread)")
    print("| scene | competitor | run | target | error % | study CPU s | CPU s (counted) | set-up | solves "
          "| other march | output | set-up share | notes |")
    print("|" + "---|" * 13)
    for pick in picks(args.tables, args.scenes, args.solvers):
        print(row(pick, args.budget, args.tiny), flush=True)
    print(f"load average at the end {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
