"""Command line (CONTRACT.md): ``smfem cases | run | study | report``.

User mistakes end with one line on stderr and exit status 2; a run that fails to converge ends
with exit status 3 after writing the history up to the last converged step.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

from cases import CASES, ParameterError, UnsupportedCase, get_case, parse_sets
from reports.cli import add_commands, run_command

EXIT_USAGE, EXIT_NOT_CONVERGED = 2, 3


class UsageError(Exception):
    """A user mistake with a one-line explanation."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        raise UsageError(message)


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="smfem", description="Semi-analytic FEM for transient dynamics, verified against scikit-fem.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    sub.add_parser("cases", help="list cases, their variants and parameters")
    run = sub.add_parser("run", help="run one case and write history.csv, summary.json, fields.vtu")
    run.add_argument("case")
    run.add_argument("--solver", choices=("smfem", "reference"), default="smfem")
    run.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE")
    run.add_argument("--out", default=None, help="output directory (default: out/CASE-SOLVER)")
    run.add_argument("--no-fields", action="store_true", help="do not write fields.vtu")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    cmp = sub.add_parser("compare", help="run a case with SMFEM and the reference FEM and compare them")
    cmp.add_argument("case")
    cmp.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE",
                     help="for both solvers")
    cmp.add_argument("--smfem-set", dest="smfem_sets", action="append", default=[], metavar="KEY=VALUE")
    cmp.add_argument("--reference-set", dest="reference_sets", action="append", default=[], metavar="KEY=VALUE")
    cmp.add_argument("--out", default=None, help="output directory (default: out/CASE-compare)")
    add_commands(sub)
    return p


def list_cases() -> str:
    lines = []
    for name, module in CASES.items():
        lines.append(f"{name}: {module.TITLE}")
        for key, spec in module.SPECS.items():
            default = module.DEFAULTS.get(key)
            lines.append(f"    {key:<12} default {default!s:<22} {spec.describe()}  {spec.help}")
    return "\n".join(lines)


def check_writable(out: Path) -> None:
    """Fail early, before any work and without leaving anything, if ``out`` cannot be written.

    Tries to make a scratch directory in the nearest existing ancestor: permission bits alone
    do not tell (root, read-only or virtual file systems).
    """
    probe = out.absolute()
    while not probe.exists():
        probe = probe.parent
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {out}: exists and is not a directory")
    try:
        os.rmdir(tempfile.mkdtemp(dir=probe, prefix=".smfem-write-test-"))
    except OSError as exc:
        raise UsageError(f"--out {out}: cannot write there ({exc.strerror})") from None


def solver_function(name: str):
    if name == "smfem":
        from smfem.solver import solve
    else:
        from reference_fem import solve
    return solve


def run(args) -> int:
    case = get_case(args.case, parse_sets(args.sets))
    out = Path(args.out or f"out/{case.name}-{args.solver}")
    check_writable(out)
    solve = solver_function(args.solver)
    from tqdm import tqdm

    bar = tqdm(total=case.n_steps, desc=f"{case.name} ({args.solver})", unit="step",
               disable=args.quiet or None, file=sys.stderr, leave=False)
    progress = lambda step, n: bar.update(step - bar.n)
    wall0 = time.perf_counter()
    try:
        options = {"with_fields": not args.no_fields} if args.solver == "smfem" else {}
        result = solve(case, progress=progress, **options)
    finally:
        bar.close()
    wall = time.perf_counter() - wall0
    from smfem.output import write_run

    write_run(out, case, args.solver, result, wall)
    if not result.converged:
        print(f"smfem: {case.name}: {result.message}", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    print(f"{case.name} ({args.solver}): {len(result.iterations)} steps, {result.n_dof} dof, "
          f"cpu {result.cpu_time_s:.3g} s -> {out}")
    return 0


def compare(args) -> int:
    both = parse_sets(args.sets)
    s_case = get_case(args.case, {**both, **parse_sets(args.smfem_sets)})
    r_case = get_case(args.case, {**both, **parse_sets(args.reference_sets)})
    out = Path(args.out or f"out/{s_case.name}-compare")
    check_writable(out)
    from smfem.compare import compare as run_both

    table = run_both(s_case, r_case, out)
    print(table.to_string(index=False, float_format=lambda x: f"{x:.4g}"))
    print(f"-> {out}")
    return 0


COMMANDS = {"run": run, "compare": compare}


def main(argv=None) -> int:
    try:
        args = build_parser().parse_args(argv)
        if args.command == "cases":
            print(list_cases())
            return 0
        return COMMANDS[args.command](args) if args.command in COMMANDS else run_command(args)
    except (UsageError, ParameterError, UnsupportedCase) as exc:
        print(f"smfem: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except MemoryError:
        print("smfem: error: out of memory: the model is too large for this machine (lower refine or harmonics)",
              file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:  # the reader went away (`smfem cases | head`): not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at exit
        return 0


if __name__ == "__main__":
    sys.exit(main())
