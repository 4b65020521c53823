"""``smfem run CASE``: one run, written as history.csv, summary.json, fields.vtu."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from cases import get_case, parse_sets
from runs.files import write_run
from runs.progress import Progress
from runs.registry import CALCULIX, EXPLICIT, REFERENCE, SMFEM, solve

from .usage import EXIT_NOT_CONVERGED, UsageError, add_sets, check_writable


def add(sub) -> None:
    run = sub.add_parser("run", help="run one case and write history.csv, summary.json, fields.vtu")
    run.add_argument("case")
    run.add_argument("--solver", choices=(SMFEM, REFERENCE, CALCULIX, EXPLICIT), default=SMFEM,
                     help="calculix: CalculiX (ccx on PATH) on the reference mesh, --set dim=2|3; "
                          "reference-explicit: the reference's mesh with central differences on a lumped "
                          "mass at half the critical step (the truth engine; dt is the output interval)")
    add_sets(run)
    run.add_argument("--out", default=None, help="output directory (default: out/CASE-SOLVER)")
    run.add_argument("--no-fields", action="store_true", help="do not write fields.vtu")
    run.add_argument("--every", type=int, default=0, metavar="N",
                     help="also write fields.pvd, a ParaView time series with the field every N steps")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.set_defaults(handler=command)


def command(args) -> int:
    case = get_case(args.case, parse_sets(args.sets))
    if args.every < 0 or args.every > case.n_steps:
        raise UsageError(f"--every {args.every}: between 1 and the case's {case.n_steps} steps (0: no time series)")
    out = Path(args.out or f"out/{case.name}-{args.solver}")
    check_writable(out)
    if args.solver == CALCULIX and args.every:
        raise UsageError("--every: the time series is written by smfem and reference only")
    bar = Progress(case.n_steps, f"{case.name} ({args.solver})", "step", enabled=not args.quiet, leave=False)
    wall0 = time.perf_counter()
    try:
        result = solve(args.solver, case, progress=lambda step, n: bar.update(step),
                       fields=not args.no_fields, every=args.every)
    finally:
        bar.close()
    write_run(out, case, args.solver, result, time.perf_counter() - wall0)
    if not result.converged:
        print(f"smfem: {case.name}: {result.message}", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    print(f"{case.name} ({args.solver}): {len(result.iterations)} steps, {result.n_dof} dof, "
          f"cpu {result.cpu_time_s:.3g} s -> {out}")
    return 0
