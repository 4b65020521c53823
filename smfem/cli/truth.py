"""``smfem truth CASE``: a case's truth, converged in mesh, harmonics and time
(:mod:`smfem.studies.truth`): history.csv and summary.json with per-probe uncertainty.

With ``--full`` the truth is the one the repository stores (``smfem/truths/CASE``, the default
output then, when no ``--set`` changes the scene): it is made on its own path and on a second,
independent one (``OUT/second``), and ``summary.json`` carries the distance between the two
(:mod:`smfem.studies.calibration`) and the key that ties it to the case and the method
(:mod:`smfem.studies.stored`).
"""

from __future__ import annotations

import sys
from pathlib import Path

from cases import get_case, parse_sets
from .usage import EXIT_NOT_CONVERGED, UsageError, add_sets, add_study_options, check_workers, check_writable

#: keys a truth chooses itself
TRUTH_KEYS = ("refine", "harmonics", "dim")


def add(sub) -> None:
    truth = sub.add_parser("truth", help="a case's truth, converged in mesh, harmonics and time: history.csv, "
                                         "summary.json with per-probe uncertainty (--full: the stored truth, "
                                         "written to smfem/truths/CASE)")
    truth.add_argument("case", help="a built-in scene or a scene file (NAME.toml)")
    add_sets(truth, "case parameters (the truth chooses refine, harmonics and dim; dt sets its time grid)")
    add_study_options(truth, None)
    truth.set_defaults(handler=command)


def command(args) -> int:
    """Run (or take from the cache) the truth's levels, write ``history.csv`` and
    ``summary.json``; 3 if a level it needs stopped without a history."""
    from smfem.studies.calibration import calibrate, second_plan, widen
    from smfem.studies.executors import SchedulerUnreachable
    from smfem.studies.own_scene import scene_ref
    from smfem.studies.stored import key_of
    from smfem.studies.truth import plan_for

    check_workers(args)
    base = parse_sets(args.sets)
    chosen = [k for k in TRUTH_KEYS if k in base]
    if chosen:
        raise UsageError(f"--set {chosen[0]}: the truth chooses {', '.join(TRUTH_KEYS)} itself (its levels)")
    args.case = scene_ref(args.case)  # a scene file by its absolute path: workers read it wherever they run
    case = get_case(args.case, base)  # a bad case, key or value: exit 2 before anything is written
    stored = args.full and not base and case.source is None  # a scene file's truth is the user's
    out = Path(args.out or (f"smfem/truths/{case.name}" if stored else f"out/{case.name}-truth"))
    check_writable(out)
    cache = Path(args.cache or ("out/truth-runs" if stored else out / "runs"))
    plan = plan_for(args.case, base, "full" if args.full else "quick")
    paths = [("truth", plan)] + ([("second path", second_plan(args.case, plan))] if args.full else [])
    made = {}
    try:
        for role, p in paths:
            made[role] = _make(args, base, p, cache, role)
            if made[role] is None:
                return EXIT_NOT_CONVERGED
    except SchedulerUnreachable as exc:
        raise UsageError(str(exc)) from None
    truth = made["truth"]
    if args.full:
        truth.key = key_of(case, plan)
        truth.calibration = calibrate(case, truth, made["second path"])
        widen(truth, truth.calibration)
        made["second path"].write(out / "second")
    truth.write(out)
    print(f"{truth.name}")
    for probe, u in truth.uncertainty.items():
        note = truth.notes.get(probe, "")
        cal = truth.calibration.get("probes", {}).get(probe) if truth.calibration else None
        against = (f"  second path {100 * cal['distance']:.3g} % away (its own {100 * cal['second_uncertainty']:.3g} %)"
                   if cal else "")
        print(f"  {probe:<12} uncertainty {100 * u:.3g} %{against}  {note}".rstrip())
    print(f"truth: CPU {truth.cpu_time_s:.3g} s -> {out}/")
    return 0


def _make(args, base: dict, plan, cache: Path, role: str):
    """One truth path from its runs (cached); None (and a message) if a level has no history."""
    from smfem.studies.cache import RunCache
    from smfem.studies.study import run_cached
    from smfem.studies.truth import assemble, jobs

    wanted = jobs(args.case, plan, base)
    runs, executed, cached = run_cached(list(wanted.values()), RunCache(cache), args.scheduler, args.workers,
                                        not args.quiet)
    print(f"{role}: {len(executed)} runs executed, {cached} cached")
    truth = assemble(args.case, plan, base, {r: runs[j] for r, j in wanted.items()})
    if truth is None:
        bad = [f"{j.describe()}: {runs[j].status}: {runs[j].message}" for j in wanted.values() if not runs[j].usable]
        print(f"smfem: truth of {args.case}: a level has no history ({'; '.join(bad)})", file=sys.stderr)
    return truth
