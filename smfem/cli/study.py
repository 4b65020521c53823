"""``smfem study CASE ...`` and ``smfem report``: series of runs, errors against the truth,
work-precision; the report adds index.html and report.pdf (:mod:`reports.build`)."""

from __future__ import annotations

import sys
from pathlib import Path

from .usage import UsageError, add_study_options, check_workers, check_writable


def add(sub) -> None:
    study = sub.add_parser("study", help="convergence and error-against-CPU-time study: tables/*.csv, figures/")
    study.add_argument("cases", nargs="+", metavar="CASE", help="built-in scenes or scene files (NAME.toml: a "
                                                                "study made for the scene, docs/usage.md)")
    add_study_options(study, "out/study")
    study.add_argument("--solvers", nargs="+", default=(), metavar="SOLVER",
                       help="only these solvers' series (names as in tables/fronts.csv: smfem reference-2d ...): "
                            "SMFEM against one competitor without the others' runs")
    _store_fronts(study)
    _timing(study)
    study.set_defaults(handler=command)
    report = sub.add_parser("report", help="the verification report: index.html, report.pdf, tables/*.csv")
    report.add_argument("cases", nargs="*", metavar="CASE", help="only these scenes, built-in or from files "
                                                                 "(NAME.toml); default: every scene of the plan")
    add_study_options(report, "out/report")
    _store_fronts(report)
    _timing(report)
    report.add_argument("--retime", action="store_true",
                        help="redo only the timing pass on the report in --out (its run cache, the same scenes and "
                             "--quick/--full): runs no solver but the re-timed runs, every run behind the headline, "
                             "the dear ones too, and writes the tables and index.html, report.pdf again")
    report.add_argument("--publish", default=None, metavar="DIR",
                        help="also keep tables/headline.csv, fronts.csv, carried.csv, timing.csv and run.json (wall time, machine, "
                             "peak memory) in DIR: the findings README quotes (docs/full-report for --full)")
    report.set_defaults(handler=command)


def _timing(parser) -> None:
    from smfem.studies.timing import BUDGET_S, TimingRule

    rule, quick = TimingRule(), TimingRule.of(False)
    parser.add_argument("--timing-budget", type=float, default=BUDGET_S, metavar="SECONDS",
                        help=f"the timing pass after the runs times each run behind the headline again, alone and "
                             f"by turns with its competitor, to {rule.repeats} repeats and {rule.total_s:g} CPU s, and "
                             f"{rule.settle_s:g} CPU s and {rule.settle_repeats} repeats or {rule.max_repeats} repeats, "
                             f"spread over {rule.sweeps} sweeps, and a second repeat within {100 * rule.hold:g} %% of its "
                             f"minimum (tables/timing.csv); a run over {rule.long_s:g} s is timed once, and once more while "
                             f"the pass stays within this many CPU s (default {BUDGET_S:g}); 0: never twice. The "
                             f"quick settings time only runs whose study shot took at most "
                             f"{quick.kept_s:g} s: a dearer run's shot stands (0 repeats; --retime times it), "
                             f"and stop at {quick.repeats} repeats and {quick.total_s:g} CPU s over "
                             f"{quick.sweeps} sweeps. No pass times a run whose shot is over "
                             f"{quick.rivals:g} times its rival's (SMFEM's other element, the other engine "
                             f"or procedure): it cannot decide its cost")
    parser.add_argument("--no-timing", action="store_true",
                        help="no timing pass: the headline keeps the study's single-shot CPU times")


def _store_fronts(parser) -> None:
    parser.add_argument("--store-fronts", action="store_true",
                        help="keep each scene's measured work-precision points (tables/fronts.csv) with its stored "
                             "truth, as smfem/truths/CASE/front.csv: where smfem run --tol starts (a study: its scenes' only)")


def command(args) -> int:
    """1 if a run failed with an error (the outputs are written all the same), else 0."""
    from reports.timing import timed_runs
    from smfem import api  # the reports load matplotlib, jinja2, dask: only when asked
    from smfem.studies.executors import SchedulerUnreachable
    from smfem.studies.jobs import FAILED
    from smfem.studies.study import NotInCache

    check_workers(args)
    out = Path(args.out)
    check_writable(out)
    publish_to = getattr(args, "publish", None) and Path(args.publish)
    if publish_to:
        check_writable(publish_to, "--publish")
    retime = getattr(args, "retime", False)
    if retime and args.no_timing:
        raise UsageError("--retime redoes the timing pass: it cannot go with --no-timing")
    if args.timing_budget < 0:
        raise UsageError(f"--timing-budget={args.timing_budget:g}: a budget is at least 0 CPU s")
    budget = None if args.no_timing else args.timing_budget
    try:
        if args.command == "report":
            report = api.report(out=out, full=args.full, scenes=tuple(args.cases), cache=args.cache,
                                scheduler=args.scheduler, workers=args.workers, progress=not args.quiet,
                                timing_budget_s=budget, retime=retime)
        else:
            report = api.study(out=out, full=args.full, scenes=tuple(args.cases), cache=args.cache,
                               scheduler=args.scheduler, workers=args.workers, progress=not args.quiet,
                               timing_budget_s=budget, solvers=tuple(args.solvers))
    except (SchedulerUnreachable, NotInCache) as exc:
        raise UsageError(str(exc)) from None
    for line in headline_lines(report.tables["headline"]):
        print(line)
    made = "index.html, report.pdf, " if args.command == "report" else ""
    timed = timed_runs(report.tables["timing"])
    print(f"{args.command}: {len(report.study.executed)} runs executed, {report.study.cached} cached, "
          f"{len(timed)} runs timed again ({int(timed.repeats.sum())} repeats), "
          f"{report.wall_time_s:.1f} s -> {out}/ ({made}tables/, figures/)")
    if publish_to:
        from reports.publish import publish

        made = publish(report, publish_to, "full" if args.full else "quick", args.workers, args.scheduler)
        print(f"{args.command}: published to {publish_to}/ (tables/, run.json: {made['wall_time_s']:.0f} s wall, "
              f"largest run {made['peak_memory_mb']} MB)")
    if getattr(args, "store_fronts", False):
        from smfem.studies.stored import write_fronts

        written = write_fronts(report.tables["fronts"])
        print(f"{args.command}: fronts kept for {', '.join(written) or 'no scene (none measured against its stored truth)'}")
    failed = [r for an in report.analyses for r in an.runs.all_runs() if r.status == FAILED]
    for run in failed:
        print(f"smfem: {run.job.describe()}: failed: {run.message}", file=sys.stderr)
    return 1 if failed else 0


def headline_lines(head) -> list[str]:
    """The headline in a few short lines (the whole table is tables/headline.csv): per case and
    target, SMFEM's cost with its cheaper element there and its speed-up over each other solver
    (over the 3D reference: its cheaper engine there, named)."""
    from reports.verdict import cheapest, engine, split_smfem

    lines = []
    width = max((len(c) for c in head.case), default=0)
    for case, rows in head.groupby("case", sort=False):
        mine, others_rows = split_smfem(rows.set_index("solver"))
        for column in (c for c in rows.columns if c.startswith("cpu_s_to_")):
            target = column.removeprefix("cpu_s_to_").replace("pct", " %")
            best, cost = cheapest(mine, column)
            if cost:
                cost = f"{cost.group(1)} s CPU ({cost.group(2)})"
            else:  # not reached: the first element's cell says how far it came
                best = mine.index[0] if len(mine) else "smfem"
                cost = str(mine.at[best, column]) if len(mine) else ""
            others = []
            for solver, row in others_rows.iterrows():
                speedup = row.get(f"smfem_speedup_{column.removeprefix('cpu_s_to_')}")
                if isinstance(speedup, str) and speedup:
                    which = engine(solver, row[column])
                    others.append(f"{solver} {speedup}" + (f" ({which})" if which else ""))
                elif str(row[column]).startswith("not available"):
                    others.append(f"{solver} not available")
            lines.append(f"{case:<{width}}  {target:>4}: {best} {cost}" + (f"; speed-up over {', '.join(others)}" if others else ""))
    return lines
