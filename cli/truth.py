"""``smfem truth CASE``: a case's truth, converged in mesh, harmonics and time
(:mod:`reports.truth`): history.csv and summary.json with per-probe uncertainty."""

from __future__ import annotations

import sys
from pathlib import Path

from cases import get_case, parse_sets
from .usage import EXIT_NOT_CONVERGED, UsageError, add_sets, add_study_options, check_workers, check_writable

#: keys a truth chooses itself
TRUTH_KEYS = ("refine", "harmonics", "dim")


def add(sub) -> None:
    truth = sub.add_parser("truth", help="a case's truth, converged in mesh, harmonics and time: history.csv, "
                                         "summary.json with per-probe uncertainty")
    truth.add_argument("case")
    add_sets(truth, "case parameters (the truth chooses refine, harmonics and dim; dt sets its time grid)")
    add_study_options(truth, None)
    truth.set_defaults(handler=command)


def command(args) -> int:
    """Run (or take from the cache) the truth's levels, write ``history.csv`` and
    ``summary.json``; 3 if a level it needs stopped without a history."""
    from reports.cache import RunCache
    from reports.executors import SchedulerUnreachable
    from reports.study import run_cached
    from reports.truth import assemble, jobs, plan_for

    check_workers(args)
    base = parse_sets(args.sets)
    chosen = [k for k in TRUTH_KEYS if k in base]
    if chosen:
        raise UsageError(f"--set {chosen[0]}: the truth chooses {', '.join(TRUTH_KEYS)} itself (its levels)")
    get_case(args.case, base)  # a bad case, key or value: exit 2 before anything is written
    out = Path(args.out or f"out/{args.case}-truth")
    check_writable(out)
    plan = plan_for(args.case, base, "full" if args.full else "quick")
    wanted = jobs(args.case, plan, base)
    try:
        runs, executed, cached = run_cached(list(wanted.values()), RunCache(Path(args.cache or out / "runs")),
                                            args.scheduler, args.workers, not args.quiet)
    except SchedulerUnreachable as exc:
        raise UsageError(str(exc)) from None
    truth = assemble(args.case, plan, base, {role: runs[job] for role, job in wanted.items()})
    if truth is None:
        bad = [f"{j.describe()}: {runs[j].status}: {runs[j].message}" for j in wanted.values() if not runs[j].usable]
        print(f"smfem: truth of {args.case}: a level has no history ({'; '.join(bad)})", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    truth.write(out)
    print(f"{truth.name}")
    for probe, u in truth.uncertainty.items():
        note = truth.notes.get(probe, "")
        print(f"  {probe:<12} uncertainty {100 * u:.3g} %  {note}".rstrip())
    print(f"truth: {len(executed)} runs executed, {cached} cached, CPU {truth.cpu_time_s:.3g} s -> {out}/")
    return 0
