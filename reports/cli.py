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


def _options(p, default_out: str) -> None:
    size = p.add_mutually_exclusive_group()
    size.add_argument("--quick", action="store_true", help="the quick study (the default; minutes on two cores)")
    size.add_argument("--full", action="store_true", help="the larger study")
    p.add_argument("--out", default=default_out, help=f"output directory (default {default_out})")
    p.add_argument("--cache", default=None, help="run cache directory (default OUT/runs)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="dask.distributed scheduler address (default: local processes)")
    p.add_argument("--workers", type=int, default=2, help="local worker processes (default 2)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def run_command(args) -> int:
    """Run ``smfem study`` or ``smfem report``; 1 if a run failed with an error (the outputs
    are written all the same), else 0."""
    from smfem.cli import UsageError, check_writable

    from .build import build
    from .executors import SchedulerUnreachable
    from .jobs import FAILED

    if args.workers < 1:
        raise UsageError(f"--workers={args.workers} is out of range: --workers must be an integer >= 1")
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
