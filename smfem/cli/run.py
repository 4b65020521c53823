"""``smfem run CASE``: one run, written as history.csv, summary.json, fields.vtu."""

from __future__ import annotations

import math
import sys
from pathlib import Path

from cases import get_case, parse_sets, rebuild
from cases.params import parse_option
from smfem.runs import validity
from smfem.runs.estimate import summary_line
from smfem.runs.registry import FRAMES, SMFEM, lookup, named_for, solvers
from smfem.runs.tolerance import search

from smfem.api import Result, claimed

from .usage import EXIT_NOT_CONVERGED, UsageError, add_sets, check_writable


def add(sub) -> None:
    run = sub.add_parser("run", help="run one case and write history.csv, summary.json, fields.vtu")
    run.add_argument("case")
    run.add_argument("--solver", choices=[s.name for s in solvers() if s.command_line], default=SMFEM,
                     help="calculix: CalculiX (ccx on PATH) on the reference mesh, --set dim=2|3; "
                          "reference-explicit: the reference's mesh with central differences on a lumped "
                          "mass at half the critical step (the truth engine; dt is the output interval)")
    add_sets(run)
    run.add_argument("--out", default=None, help="output directory (default: out/CASE-SOLVER)")
    run.add_argument("--no-fields", action="store_true", help="do not write fields.vtu")
    run.add_argument("--every", type=int, default=0, metavar="N",
                     help="also write fields.pvd, a ParaView time series with the field every N steps")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.add_argument("--estimate", choices=("on", "off"), default="on",
                     help="the run's error estimate from cheap companion runs (coarser mesh, twice the step, "
                          "half the harmonics), in summary.json and one line; off: the run alone")
    run.add_argument("--tol", default=None, metavar="TARGET",
                     help="an accuracy to reach (1%% or 0.01): runs from the case's settings up, refining what the "
                          "estimate says holds the error up, until the estimate meets it (exit 3 if not within --max-cpu)")
    run.add_argument("--max-cpu", type=float, default=600.0, metavar="S",
                     help="CPU seconds --tol may spend, runs and companions together (default 600)")
    run.set_defaults(handler=command)


def split_sets(items, solver: str) -> tuple[dict, dict]:
    """``--set`` items as the case's overrides and the solver's own options (a field of SMFEM's
    ``SolverOptions``, or the reference's ``grading``: the names its table entry gives); an
    option's value may be a bare word (``iteration_matrix=sor``)."""
    mine = lookup(solver).options()
    others = {}  # option -> the first solver (by family name) that takes it
    for s in solvers():
        for name in s.options().keys() - mine.keys():
            others.setdefault(name, s.family)
    case_items, options = [], {}
    for item in items or ():
        key, sep, text = (part.strip() for part in item.partition("="))
        if key in others:
            raise UsageError(f"--set {key}: an option of {others[key]}, not of {solver}")
        if key not in mine:
            case_items.append(item)
        elif not text:
            raise UsageError(f"malformed --set {item!r}: expected KEY=VALUE")
        else:
            options[key] = parse_option(key, text)
    return parse_sets(case_items), options


#: the largest --max-cpu, s (a year): every bound finite, as the parameters' are
MAX_CPU_S = 3.2e7


def command(args) -> int:
    if not 0 < args.max_cpu <= MAX_CPU_S:  # NaN fails too
        raise UsageError(f"--max-cpu {args.max_cpu:g} is out of range: CPU seconds in (0, {MAX_CPU_S:g}]")
    sets, given = split_sets(args.sets, args.solver)
    case = get_case(args.case, sets)
    try:
        args.options = lookup(args.solver).make_options(given) if given else None  # checked before any run
    except (TypeError, ValueError) as exc:
        raise UsageError(f"--set: {exc}") from None
    args.given_options = {"options": given} if given else {}  # summary.json: how the run was solved
    if args.every < 0 or args.every > case.n_steps:
        raise UsageError(f"--every {args.every}: between 1 and the case's {case.n_steps} steps (0: no time series)")
    out = Path(args.out or f"out/{case.name}-{args.solver}")
    check_writable(out)
    if args.every and FRAMES not in lookup(args.solver).supports:
        raise UsageError(f"--every: {args.solver} writes no time series")
    if args.tol is not None:
        return _to_tolerance(case, args, out)
    from smfem import api

    run = api.run(case, args.solver, estimate=args.estimate == "on", fields=not args.no_fields, every=args.every,
                  progress=not args.quiet, out=out, **given)  # written before its companions start
    warning = validity.warning_line(case, run.extra["validity"])
    if warning:
        print(warning, file=sys.stderr)
    result = run.raw
    if not result.converged:
        print(f"smfem: {case.name}: {result.message}", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    print(f"{case.name} ({args.solver}): {len(result.iterations)} steps, {result.n_dof} dof, "
          f"cpu {result.cpu_time_s:.3g} s -> {out}")
    if run.error_estimate is not None:
        print(summary_line(case, args.solver, run.error_estimate))
    return 0


def _write_checked(out: Path, case, solver: str, result, wall_s: float, est: dict | None = None, **extra) -> dict:
    """Write the run with its validity (and error estimate, where made already), print the
    validity warning if any; returns the validity."""
    check = validity.check(case, result)
    Result(case, solver, result, wall_s, None if est is None else claimed(check, est),
           {"validity": check, **extra}).write(out)
    warning = validity.warning_line(case, check)
    if warning:
        print(warning, file=sys.stderr)
    return check


def parse_target(text: str) -> float:
    """``1%`` or ``0.01`` as a fraction; a clear error otherwise."""
    t = text.strip()
    try:
        value = float(t[:-1]) / 100 if t.endswith("%") else float(t)
    except ValueError:
        raise UsageError(f"--tol {text!r}: give a relative accuracy, 1% or 0.01") from None
    if not 0 < value < 1:
        raise UsageError(f"--tol {text!r}: between 0 and 100 %")
    return value


def _stored_truth(case):
    """A built-in scene's stored truth, while ``case`` has its physics (:func:`smfem.api.truth`)."""
    from smfem.api import truth

    return truth(case)


def _truth_floor(case, truth) -> float | None:
    """Three times the stored ``truth``'s uncertainty over a built-in scene's displacement and
    velocity probes (what no run can be shown to beat); None without a stored truth of the
    case's physics."""
    from smfem.studies.metrics import TRUTH_MARGIN

    if truth is None:
        return None
    u = truth.uncertainty_of([p.name for p in case.probes if p.field in ("u", "v")])
    return TRUTH_MARGIN * u if u == u else None


def _front_start(case, truth, solver: str, target: float):
    """Where ``--tol`` starts on a built-in scene whose front is stored (``smfem/truths/CASE/front.csv``,
    measured against the same truth): the cheapest measured settings within ``target``, else the
    most accurate; (overrides, their measured error) or None."""
    from smfem.studies.stored import read_front

    front = read_front(case.name) if truth is not None else None
    if front is None:
        return None
    # the case's own time scheme only: the measured settings of another scheme do not carry over
    scheme = front["time_scheme"].fillna("newmark") if "time_scheme" in front else "newmark"
    rows = front[(front.solver == named_for(solver, case)) & front.total.notna()
                 & (scheme == case.params.get("time_scheme", "newmark"))]
    if not len(rows):
        return None
    within = rows[rows.total <= target]
    row = within.sort_values("cpu_s").iloc[0] if len(within) else rows.sort_values("total").iloc[0]
    over = {"refine": int(row.refine), "harmonics": int(row.harmonics), "dt": float(row["dt"])}
    if row.coarsen == row.coarsen and row.coarsen:  # NaN: not coarsened
        over["coarsen"] = int(row.coarsen)
    elif "coarsen" in case.params:
        over["coarsen"] = 1
    return over, float(row.total)


def _settings(case) -> str:
    coarsen = case.params.get("coarsen", 1)
    return f"refine {case.refine}" + (f", coarsen {coarsen}" if coarsen > 1 else "") + \
        f", harmonics {case.harmonics}, dt {case.dt:.3g}"


def _estimated(attempt) -> str:
    if math.isinf(attempt.error):
        return "no estimate"
    missing = ", ".join(attempt.estimate.get("unmeasured", {}))
    return f"estimated {100 * attempt.error:.3g} %" + (f" (partial: {missing} not measured)" if missing else "")


def _achieved(attempt) -> str:
    if attempt.measured is None:
        return _estimated(attempt)
    return f"measured {100 * attempt.measured:.3g} % against the truth ({_estimated(attempt)})"


def _to_tolerance(case, args, out: Path) -> int:
    """``--tol``: the search of :mod:`smfem.runs.tolerance`, one line per run, the best run written."""
    target = parse_target(args.tol)
    if not lookup(args.solver).estimated:
        estimated = " or ".join(s.name for s in solvers() if s.estimated and s.command_line)
        raise UsageError(f"--tol needs the error estimate ({estimated}), not {args.solver}")
    truth = _stored_truth(case)  # read once: the floor and the front both need it
    floor = _truth_floor(case, truth)
    if floor is not None and target < floor:
        raise UsageError(f"--tol {args.tol}: below three times {case.name}'s stored truth uncertainty "
                         f"({100 * floor:.2g} %): no run can be shown to reach it")
    start = _front_start(case, truth, args.solver, target)
    if args.estimate == "off" and (start is None or start[1] > target):
        raise UsageError(f"--tol {args.tol} --estimate off: only where a built-in scene's measured front reaches the "
                         "target (its error against the truth stands for the run's); elsewhere --tol needs the estimate")
    measured = None
    if start is not None:
        case, measured = rebuild(case, start[0]), start[1]
        print(f"--tol {100 * target:g} %: {case.name}'s measured front (smfem/truths/{case.name}/front.csv) starts at "
              f"{_settings(case)}, {100 * measured:.3g} % against the stored truth")
    def written(run_case, result, wall_s):  # each finished run on disk before its companions start
        _write_checked(out, run_case, args.solver, result, wall_s, **args.given_options)

    found = search(case, args.solver, target, args.max_cpu, fields=not args.no_fields, measured=measured,
                   estimated=args.estimate == "on", options=args.options, on_run=written)
    for k, a in enumerate(found.attempts, start=1):
        known = f"measured {100 * a.measured:.3g} % against the truth, " if a.measured is not None else ""
        print(f"--tol {100 * target:g} %: run {k} ({_settings(a.case)}): {known}{_estimated(a)}, "
              f"{a.cpu_s:.3g} s CPU" + ("" if math.isinf(a.error) else " with its companions"))
    if not found.attempts:
        print(f"smfem: {case.name}: --tol: the first run did not finish", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    best = found.best
    tolerance = {"target": target, "met": found.met, "runs": [
        {"settings": {"refine": a.case.refine, "coarsen": a.case.params.get("coarsen", 1),
                      "harmonics": a.case.harmonics, "dt": a.case.dt},
         "estimate": None if math.isinf(a.error) else a.error, "measured_against_truth": a.measured,
         "valid": a.valid, "cpu_s": a.cpu_s} for a in found.attempts], "cpu_s": found.cpu_s}
    _write_checked(out, best.case, args.solver, best.result, best.wall_s,
                   best.estimate if args.estimate == "on" else None, tolerance=tolerance, **args.given_options)
    outside = "" if best.valid else " (outside the small-strain model: no accuracy of the physical body is claimed)"
    if not found.met:
        why = f"({found.stopped})" if found.stopped else f"within --max-cpu {args.max_cpu:g} s"
        print(f"smfem: {case.name}: --tol {100 * target:g} % not met {why}: best "
              f"{_achieved(best)} ({_settings(best.case)}){outside}, kept in {out}", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    print(f"{case.name} ({args.solver}): --tol {100 * target:g} % met: {_achieved(best)} at "
          f"{_settings(best.case)}, {found.cpu_s:.3g} s CPU in {len(found.attempts)} runs{outside} -> {out}")
    return 0
