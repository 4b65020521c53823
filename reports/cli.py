"""The ``smfem study`` and ``smfem report`` subcommands (wired into :mod:`smfem.cli`).

Kept light at import: ``smfem run`` loads this module too.
"""

from __future__ import annotations

import sys
from pathlib import Path

from .plan import full, quick, select


def add_commands(sub) -> None:
    """Add ``study`` and ``report`` to the subparsers ``sub`` of the ``smfem`` parser."""
    study = sub.add_parser("study", help="convergence and error-against-CPU-time study: tables/*.csv, figures/")
    study.add_argument("cases", nargs="+", metavar="CASE")
    _options(study, "out/study")
    report = sub.add_parser("report", help="the verification report: index.html, report.pdf, tables/*.csv")
    _options(report, "out/report")
    truth = sub.add_parser("truth", help="a case's truth, converged in mesh, harmonics and time: history.csv, "
                                         "summary.json with per-probe uncertainty")
    truth.add_argument("case")
    truth.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                       help="case parameters (the truth chooses refine, harmonics and dim; dt sets its time grid)")
    _options(truth, None)


def _options(p, default_out: str | None) -> None:
    size = p.add_mutually_exclusive_group()
    size.add_argument("--quick", action="store_true", help="the quick study (the default; minutes on two cores)")
    size.add_argument("--full", action="store_true", help="the larger study")
    p.add_argument("--out", default=default_out, help=f"output directory (default {default_out or 'out/CASE-truth'})")
    p.add_argument("--cache", default=None, help="run cache directory (default OUT/runs)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="dask.distributed scheduler address (default: local processes)")
    p.add_argument("--workers", type=int, default=2, help="local worker processes (default 2)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


#: keys a truth chooses itself
TRUTH_KEYS = ("refine", "harmonics", "dim")


def run_command(args) -> int:
    """Run ``smfem study``, ``smfem report`` or ``smfem truth``; 1 if a run failed with an
    error (the outputs are written all the same), else 0."""
    from smfem.cli import UsageError

    if args.workers < 1:
        raise UsageError(f"--workers={args.workers} is out of range: --workers must be an integer >= 1")
    return truth_command(args) if args.command == "truth" else _study_command(args)


def truth_command(args) -> int:
    """``smfem truth CASE``: run (or take from the cache) the truth's levels, write
    ``history.csv`` and ``summary.json``; 3 if a level it needs stopped without a history."""
    from cases import get_case, parse_sets
    from smfem.cli import EXIT_NOT_CONVERGED, UsageError, check_writable

    from .cache import RunCache
    from .executors import SchedulerUnreachable
    from .study import run_cached
    from .truth import assemble, jobs, plan_for

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


def _study_command(args) -> int:
    from smfem.cli import UsageError, check_writable

    from .build import build
    from .executors import SchedulerUnreachable
    from .jobs import FAILED
    plan = select(full() if args.full else quick(), getattr(args, "cases", ()))
    out = Path(args.out)
    check_writable(out)
    try:
        report = build(plan, out, cache=args.cache and Path(args.cache), scheduler=args.scheduler,
                       workers=args.workers, progress=not args.quiet, settings="full" if args.full else "quick",
                       document=args.command == "report")
    except SchedulerUnreachable as exc:
        raise UsageError(str(exc)) from None
    print(report.tables["headline"].to_string(index=False))
    made = "index.html, report.pdf, " if args.command == "report" else ""
    print(f"{args.command}: {len(report.study.executed)} runs executed, {report.study.cached} cached, "
          f"{report.wall_time_s:.1f} s -> {out}/ ({made}tables/, figures/)")
    failed = [r for an in report.analyses for r in an.runs.all_runs() if r.status == FAILED]
    for run in failed:
        print(f"smfem: {run.job.describe()}: failed: {run.message}", file=sys.stderr)
    return 1 if failed else 0
