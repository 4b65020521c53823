"""``smfem export CASE --format inp``: the scene as an Abaqus/CalculiX input deck."""

from __future__ import annotations

import sys
from pathlib import Path

from cases import get_case, parse_sets

from .usage import UsageError, add_sets, check_writable

FORMATS = ("inp",)
#: bytes of .frd above which export warns
FRD_WARNING = 50e6


def add(sub) -> None:
    export = sub.add_parser("export", help="write the case as an Abaqus/CalculiX input deck (CASE.inp)")
    export.add_argument("case")
    add_sets(export)
    export.add_argument("--format", choices=FORMATS, default="inp", help="inp: Abaqus/CalculiX input deck")
    export.add_argument("--out", default=None, help="output directory (default: out/CASE-export)")
    export.add_argument("--frd-every", type=int, default=1, metavar="N",
                        help="results to the .frd every N increments (default 1: every one)")
    export.set_defaults(handler=command)


def command(args) -> int:
    case = get_case(args.case, parse_sets(args.sets))
    if not 1 <= args.frd_every <= case.n_steps:
        raise UsageError(f"--frd-every {args.frd_every}: between 1 and the case's {case.n_steps} steps")
    out = Path(args.out or f"out/{case.name}-export")
    check_writable(out)
    from reference_fem.calculix import build_deck

    deck = build_deck(case, every=args.frd_every)
    if deck.frd_bytes > FRD_WARNING:
        print(f"smfem: warning: ccx will write a .frd of about {deck.frd_bytes / 1e6:.0f} MB for this deck; "
              f"--frd-every N writes every Nth increment", file=sys.stderr)
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{case.name}.inp"
    path.write_text(deck.text)
    print(f"{case.name}: {deck.element} deck, {deck.cells.shape[0]} elements -> {path} (run: ccx -i {case.name})")
    return 0
