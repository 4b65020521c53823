"""README's findings, written from the published full report: the opening paragraph's numbers and
the verdict table, between markers, by ``python -m reports.readme`` from
``docs/full-report/tables/headline.csv`` and ``run.json``, never typed by hand
(``tests/test_readme.py``: every number in bold is a table cell, every loss and miss named, only
the marked blocks rewritten).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pandas as pd

from .tables import RANGE, pct_label
from .verdict import VERSUS, scene_rows, summary_table

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
PUBLISHED = ROOT / "docs" / "full-report"
#: the blocks of README this writes, each between its opening and closing marker
MARKERS = {"findings": ("<!-- findings: python -m reports.readme -->", "<!-- /findings -->"),
           "verdict": ("<!-- verdict table: python -m reports.readme -->", "<!-- /verdict table -->")}
#: a speed-up cell of the verdict table: bound, number, what it says of itself
_CELL = re.compile(r"^(?:([<>]) )?([0-9.]+)(?: \((.*)\))?$")
#: a speed-up's range over the timing pass's repeats, as the headline writes it (``'1.36e+03-4.31e+03'``)
_RANGE = re.compile(r"([0-9.]+(?:e[+-][0-9]+)?)-([0-9.]+(?:e[+-][0-9]+)?)")


def _cell(text: str) -> tuple[str, str, list[str]] | None:
    """``(bound, number, notes)`` of a speed-up cell (``'> 139'``, ``'0.49 (slower, explicit)'``), None for '-'."""
    m = _CELL.match(text)
    return (m.group(1) or "", m.group(2), m.group(3).split(", ") if m.group(3) else []) if m else None


#: scenes whose names do not read as prose with underscores made spaces
SCENE_PROSE = {"moving_load_notched": "the notched moving load", "layered_cylinder_pulse": "the layered cylinder's pulse",
               "ring_in_ring": "the rings in contact", "rod_collision": "the colliding rods"}


def scene_prose(case: str) -> str:
    """A scene as a sentence names it: 'the thick cylinder', 'the notched moving load'."""
    return SCENE_PROSE.get(case, "the " + case.replace("_", " "))


def _prose(name: str) -> str:
    """A column's solver as a sentence names it: 'the 2D FEM', 'CalculiX'."""
    return f"the {name}" if "FEM" in name else name


def _engine(notes: list[str]) -> str:
    named = [n for n in notes if n != "slower"]
    return f" ({named[0]})" if named else ""


def spread(head: pd.DataFrame, case: str, solver: str, target: float) -> tuple[float, float] | None:
    """The least and largest speed-up over ``solver`` at ``target`` that the timing pass's repeats
    allow (``smfem_speedup_*_range``: its least CPU over SMFEM's largest, and the other way round)."""
    rows = head[(head["case"] == case) & (head["solver"] == solver)]
    text = rows[f"smfem_speedup_{pct_label(target)}{RANGE}"].iloc[0] if len(rows) else None
    m = _RANGE.fullmatch(text) if isinstance(text, str) else None
    return (float(m.group(1)), float(m.group(2))) if m else None


def _measured(rows, column: int, target: float, head: pd.DataFrame) -> list[tuple[str, str, str, str]]:
    """``(verdict, number as the table shows it, scene and engine, note on its spread)`` of every measured (not bound)
    speed-up over the solver of ``column`` at ``target``, largest first; the verdict is
    ``faster``, ``slower``, or ``even``: within half a per cent (the table says nothing), or where
    the repeats' spread (:func:`spread`) reaches either side of one, whose side the host's noise,
    not the method, decides."""
    out = []
    for case, reached, _, cells in rows:
        cell = _cell(cells[column]) if reached == target else None
        if cell and not cell[0]:
            x = float(cell[1])
            low, high = spread(head, case, VERSUS[column][0], target) or (x, x)
            said = "even" if low < 1 < high else "slower" if "slower" in cell[2] else "faster" if x >= 1 else "even"
            note = f", its repeats' ratios {low:g}-{high:g}" if said == "even" and low != high else ""
            out.append((x, said, cell[1], scene_prose(case) + _engine(cell[2]), note))
    return [m[1:] for m in sorted(out, reverse=True)]


def findings(head: pd.DataFrame, made: dict) -> str:
    """The opening paragraph: where SMFEM is faster than each other solver at 1 % total error and
    by how much (every measured speed-up, in bold as the table shows it), where it is as fast or
    slower, and the scenes where it reaches only 5 % or neither target."""
    rows = scene_rows(head)
    runs = made.get("runs_stored", made["runs_executed"] + made["runs_cached"])
    text = [f"**What it found** (the full report, {runs} runs on two cores: `docs/full-report/`):"]
    for column, (_, name) in enumerate(VERSUS):
        name = _prose(name)
        measured = _measured(rows, column, 0.01, head)
        faster = [f"**{shown}**{' times' if not i else ''} on {scene}"
                  for i, (said, shown, scene, _) in enumerate(m for m in measured if m[0] == "faster")]
        even = [f"{scene} (**{shown}**{note})" for said, shown, scene, note in measured if said == "even"]
        slower = [f"{scene} (**{shown}**)" for said, shown, scene, _ in measured if said == "slower"]
        parts = []
        if faster:
            parts.append(f"faster than {name}: {_join(faster)}")
        if even:
            parts.append(f"as fast{'' if parts else f' as {name}'} on {_join(even)}")
        if slower:
            parts.append(f"slower{'' if parts else f' than {name}'} on {_join(slower)}")
        if parts:
            text.append(("at 1 % total error SMFEM is " if len(text) == 1 else "It is ") + "; ".join(parts) + ".")
    five = [f"{scene_prose(case)} ({cost} CPU s{_speedups(cells)})" for case, reached, cost, cells in rows if reached == 0.05]
    none = [f"{scene_prose(case)} (best {cost})" for case, reached, cost, _ in rows if reached is None]
    if five:
        text.append(f"It reaches 5 % but not 1 % on {_join(five)}.")
    if none:
        text.append(f"It reaches neither target on {_join(none)}.")
    text.append('A speed-up written "> x" in the table is a bound: the other solver\'s series ended above the '
                "target within its run budget.")
    return " ".join(text)


def _speedups(cells: list[str]) -> str:
    """``', speed-up **2.76** over the 3D FEM (implicit)'`` for each measured cell of a row."""
    said = ""
    for (_, name), cell in zip(VERSUS, map(_cell, cells)):
        if cell and not cell[0]:
            said += f", speed-up **{cell[1]}** over {_prose(name)}{_engine(cell[2])}"
            said += " (slower)" if "slower" in cell[2] else ""
    return said


def _join(items: list[str]) -> str:
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def blocks(head: pd.DataFrame, made: dict) -> dict[str, str]:
    """What goes between each pair of :data:`MARKERS`."""
    return {"findings": findings(head, made), "verdict": "\n".join(summary_table(head))}


def written(text: str, head: pd.DataFrame, made: dict) -> str:
    """``text`` (README) with every block of :data:`MARKERS` made from the tables again."""
    for key, body in blocks(head, made).items():
        start, end = MARKERS[key]
        pattern = re.compile(re.escape(start) + r"\n.*?\n" + re.escape(end), re.S)
        if not pattern.search(text):
            raise ValueError(f"README has no block {start} ... {end}")
        text = pattern.sub(lambda _: f"{start}\n{body}\n{end}", text)
    return text


def published(directory: Path = PUBLISHED) -> tuple[pd.DataFrame, dict]:
    """The published report's headline table and run.json."""
    return (pd.read_csv(directory / "tables" / "headline.csv"),
            json.loads((directory / "run.json").read_text()))


if __name__ == "__main__":
    README.write_text(written(README.read_text(), *published()))
    print(f"{README}: its findings and verdict table written from {PUBLISHED.relative_to(ROOT)}")
