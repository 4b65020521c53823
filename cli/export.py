"""``smfem export CASE --format inp``: the scene as an Abaqus/CalculiX input deck."""

from __future__ import annotations

from pathlib import Path

from cases import get_case, parse_sets

from .usage import add_sets, check_writable

FORMATS = ("inp",)


def add(sub) -> None:
    export = sub.add_parser("export", help="write the case as an Abaqus/CalculiX input deck (CASE.inp)")
    export.add_argument("case")
    add_sets(export)
    export.add_argument("--format", choices=FORMATS, default="inp", help="inp: Abaqus/CalculiX input deck")
    export.add_argument("--out", default=None, help="output directory (default: out/CASE-export)")
    export.set_defaults(handler=command)


def command(args) -> int:
    case = get_case(args.case, parse_sets(args.sets))
    out = Path(args.out or f"out/{case.name}-export")
    check_writable(out)
    from reference_fem.calculix import build_deck

    deck = build_deck(case)
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{case.name}.inp"
    path.write_text(deck.text)
    print(f"{case.name}: {deck.element} deck, {deck.cells.shape[0]} elements -> {path} (run: ccx -i {case.name})")
    return 0
