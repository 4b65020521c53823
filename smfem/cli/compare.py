"""``smfem compare CASE``: both solvers on one case, side by side (:mod:`reports.compare`)."""

from __future__ import annotations

from pathlib import Path

from cases import get_case, parse_sets
from smfem.runs.registry import REFERENCE, SMFEM

from .usage import add_sets, check_writable


def add(sub) -> None:
    cmp = sub.add_parser("compare", help="run a case with SMFEM and the reference FEM and compare them")
    cmp.add_argument("case")
    add_sets(cmp, "for both solvers")
    add_sets(cmp, dest="smfem_sets", flag="--smfem-set")
    add_sets(cmp, dest="reference_sets", flag="--reference-set")
    cmp.add_argument("--out", default=None, help="output directory (default: out/CASE-compare)")
    cmp.set_defaults(handler=command)


def command(args) -> int:
    both = parse_sets(args.sets)
    s_case = get_case(args.case, {**both, **parse_sets(args.smfem_sets)})
    r_case = get_case(args.case, {**both, **parse_sets(args.reference_sets)})
    out = Path(args.out or f"out/{s_case.name}-compare")
    check_writable(out)
    from reports.compare import compare

    table, cpu = compare(s_case, r_case, out)
    print(table.to_string(index=False, float_format=lambda x: f"{x:.4g}"))
    print(f"CPU time (one BLAS thread each): SMFEM {cpu[SMFEM]:.3g} s, reference {cpu[REFERENCE]:.3g} s; "
          f"SMFEM / reference = {cpu[SMFEM] / cpu[REFERENCE]:.3g}")
    print(f"-> {out}")
    return 0
