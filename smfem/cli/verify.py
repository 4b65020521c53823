"""``smfem verify [--quick | --full]``: code verification on the manufactured motions
(:mod:`reports.verification`): orders.csv and a figure per solver."""

from __future__ import annotations

import sys
import time
from pathlib import Path

from .usage import check_writable


def add(sub) -> None:
    verify = sub.add_parser("verify", help="code verification: each solver's observed orders on manufactured "
                                           "motions (orders.csv, figures/verification-SOLVER.png)")
    size = verify.add_mutually_exclusive_group()
    size.add_argument("--quick", action="store_true", help="the quick set (the default; about a minute)")
    size.add_argument("--full", action="store_true", help="finer meshes (the reference 3D at refine 4, its ring)")
    verify.add_argument("--out", default="out/verify", help="output directory (default out/verify)")
    verify.add_argument("--quiet", action="store_true", help="no progress lines")
    verify.set_defaults(handler=command)


def command(args) -> int:
    """0 when every observed order is within its tolerance of the theory's, else 1."""
    from reports.verification import ORDER_TOLERANCE, summary, verify, write

    out = Path(args.out)
    check_writable(out)
    wall0 = time.perf_counter()
    progress = None if args.quiet else (lambda i, n: print(f"verify: {i}/{n} ladders, "
                                                          f"{time.perf_counter() - wall0:.0f} s", file=sys.stderr))
    table = verify(quick=not args.full, progress=progress)
    write(table, out)
    for line in summary(table):
        print(line)
    off = table[~table.within]
    print(f"verify: {len(table) - len(off)} of {len(table)} within {ORDER_TOLERANCE:g} of the theory, "
          f"{time.perf_counter() - wall0:.1f} s -> {out}/ (orders.csv, figures/)")
    return 0 if off.empty else 1
