"""The report's verdict: one sentence per scene from the headline table, numbers included.

Where SMFEM, with the cheaper of its elements there, reaches the smallest target it can (1 %
before 5 %), at what CPU time and settings, and how that compares with each other solver at
the same target; where it reaches neither, its best error and who does better; where no claim
can be made, why.
"""

from __future__ import annotations

import math
import re

import pandas as pd

from smfem.runs.registry import lookup, solvers

from smfem.studies.metrics import TARGETS, TRUTH_TOO_COARSE
from smfem.studies.plan import SMFEM

from .tables import pct_label

_SPEEDUP = re.compile(r"^([<>]?)\s*([0-9.]+(?:e[+-]?[0-9]+)?)x$")  # 1.05e+03x: a thousand times and more
_COST = re.compile(r"^([0-9.e+-]+) \((.*)\)$")
#: the first word of a cost cell's settings (``98.6 (implicit r3 dt2.5e-06)``), or the series a
#: missed target's cell names (``not reached (best 5.1 %, explicit)``)
_NAMED = re.compile(r"^(?:[0-9.e+-]+ \((\S+)|not reached \(best [^,)]*, (\S+)\))")


def engine(solver: str, cost: str) -> str:
    """Which of a shared headline row's series a cost cell is (its :attr:`variant
    <smfem.runs.registry.Solver.variant>`: the 3D reference's ``implicit`` or ``explicit``
    engine, CalculiX's procedure), '' for a row of one series or a cell that names none."""
    variants = {s.variant for s in solvers() if s.headline == solver}
    m = _NAMED.match(str(cost).strip())
    word = (m.group(1) or m.group(2)) if m else ""
    return word if len(variants) > 1 and word in variants else ""


def names_an_engine(head: pd.DataFrame, solver: str) -> bool:
    """Some cost cell of ``solver``'s rows in the headline table (``tables/headline.csv``) names
    which of the row's series it was (:func:`engine`)."""
    rows = head[head.solver == solver]
    return any(engine(solver, cost) for c in rows.columns if c.startswith("cpu_s_to_") for cost in rows[c])


def _comparison(solver: str, speedup: str, cost: str) -> str | None:
    """``'1.05x faster than the 2D reference'`` from a speed-up cell, and which engine of a
    shared row it was (``'... than the 3D reference (explicit)'``, from its ``cost`` cell); None
    where there is none."""
    m = _SPEEDUP.match(str(speedup).strip())
    if not m:
        return None
    bound, x = m.group(1), float(m.group(2))
    which = engine(solver, cost)
    name = lookup(solver).prose + (f" ({which})" if which else "")
    if not bound and _even(x):  # 0.999x: "the 2D reference 1 times faster" said nothing
        return f"as fast as {name}"
    if x >= 1:
        more = {"<": "at most ", ">": "more than "}.get(bound, "")
        return f"{more}{_times(x)} times faster than {name}"
    less = {"<": "more than ", ">": "at most "}.get(bound, "")
    return f"{name} {less}{_times(1 / x)} times faster"


def _even(speedup: float) -> bool:
    """A speed-up within half a per cent of 1: as fast, neither faster nor slower."""
    return abs(math.log(speedup)) < 0.005


def _times(x: float) -> str:
    """Three significant digits, a thousand and more without an exponent (1050, not 1.05e+03)."""
    return f"{x:.3g}" if x < 1000 else f"{float(f'{x:.3g}'):.0f}"


def _pct_text(error_pct: float) -> str:
    return f"{error_pct:.2g} %" if math.isfinite(error_pct) else "no error measured"


def _best(mine: pd.DataFrame) -> float:
    """SMFEM's smallest error over its elements' rows, %; NaN where none was measured."""
    return min((e for e in mine.best_error_pct if math.isfinite(e)), default=math.nan)


def split_smfem(rows: pd.DataFrame) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Headline rows (indexed by solver) as SMFEM's series (one per element) and the others."""
    is_mine = [lookup(s).family == SMFEM for s in rows.index]
    return rows[is_mine], rows[[not m for m in is_mine]]


def cheapest(mine: pd.DataFrame, column: str):
    """SMFEM's element whose ``column`` (``cpu_s_to_1pct``, ...) is the cheapest cost, and that
    cell's match (CPU, settings); (None, None) where none reaches it."""
    found = [(float(m.group(1)), solver, m) for solver, row in mine.iterrows() if (m := _COST.match(str(row[column])))]
    return min(found, key=lambda f: f[0])[1:] if found else (None, None)


def sentence(case: str, rows: pd.DataFrame) -> str:
    """The verdict on one scene from its headline rows (one per solver, indexed by solver):
    SMFEM with whichever of its elements is cheapest at a target."""
    mine, others = split_smfem(rows)
    if not len(mine):
        return f"{case}: SMFEM has no run in this study."
    first = [str(c) for c in mine[f"cpu_s_to_{pct_label(TARGETS[0])}"]]
    if all(c.startswith("not available") for c in first):
        return f"{case}: SMFEM cannot run this scene ({first[0]})."
    best = _best(mine)
    for target in TARGETS:
        solver, cost = cheapest(mine, f"cpu_s_to_{pct_label(target)}")
        if cost:
            compared = [c for other, row in others.iterrows()
                        if (c := _comparison(other, row[f"smfem_speedup_{pct_label(target)}"],
                                             row[f"cpu_s_to_{pct_label(target)}"]))]
            missed = "" if target == TARGETS[0] else _missed(mine)
            there = f": {', '.join(compared)}" if compared else ""
            return (f"{case}: {lookup(solver).prose} reaches {100 * target:g} % total error in {cost.group(1)} s CPU "
                    f"({cost.group(2)}){missed}{there}.")
    if all(str(c) == TRUTH_TOO_COARSE for t in TARGETS for c in mine[f"cpu_s_to_{pct_label(t)}"]):
        return (f"{case}: no claim: the truth's uncertainty ({mine.truth_uncertainty_pct.iloc[0]:.2g} %) is too "
                f"coarse to judge {100 * TARGETS[-1]:g} %.")
    last = TARGETS[-1]
    better = [f"{lookup(s).prose} in {m.group(1)} s ({m.group(2)})" for s, row in others.iterrows()
              if (m := _COST.match(str(row[f"cpu_s_to_{pct_label(last)}"])))]
    tail = f"; {' and '.join(better)} reach{'es' if len(better) == 1 else ''} it" if better else "; no other solver does"
    return f"{case}: SMFEM does not reach {100 * last:g} % in this study (best {_pct_text(best)}){tail}."


def _missed(mine: pd.DataFrame) -> str:
    """Why a verdict at a later target is not at the first: SMFEM's best error is above it, or
    the truth cannot judge it (a scene of the user's own, whose truth the study made)."""
    first = TARGETS[0]
    if all(str(c) == TRUTH_TOO_COARSE for c in mine[f"cpu_s_to_{pct_label(first)}"]):
        return (f"; {100 * first:g} % is past what the truth can judge (its uncertainty "
                f"{mine.truth_uncertainty_pct.iloc[0]:.2g} %)")
    return f", not {100 * first:g} % (best {_pct_text(_best(mine))})"


def verdict(head: pd.DataFrame) -> list[str]:
    """One sentence per case of the headline table (``tables/headline.csv``)."""
    return [sentence(case, rows.set_index("solver")) for case, rows in head.groupby("case", sort=False)]


def _speedup_cell(speedup, which: str = "") -> str:
    """``'435'``, ``'> 19.6'``, ``'0.55 (slower)'`` from a speed-up cell, with ``which`` engine of
    a shared row it was (``'435 (implicit)'``, ``'0.55 (slower, explicit)'``); ``'-'`` where
    there is none."""
    m = _SPEEDUP.match(str(speedup).strip())
    if not m:
        return "-"
    bound, x = m.group(1), float(m.group(2))
    said = ["slower"] if x < 1 and bound != ">" and not _even(x) else []
    said += [which] if which else []
    return f"{bound + ' ' if bound else ''}{_times(x)}" + (f" ({', '.join(said)})" if said else "")


#: the solvers of the verdict table's columns, as README and the published page name them
VERSUS = (("reference-2d", "2D FEM"), ("reference-3d", "3D FEM"), ("calculix", "CalculiX"))


def scene_rows(head: pd.DataFrame, vs=VERSUS) -> list[tuple[str, float | None, str, list[str]]]:
    """Per scene of the headline table: the smallest target SMFEM reaches (1 % before 5 %; None:
    neither), its CPU time there with the cheaper element (its best error where it reaches
    none) and its speed-up cell over each of ``vs`` (:func:`_speedup_cell`; a bound where that
    solver's series ends above the target; over the 3D reference the cheaper of its two engines
    there, over CalculiX the cheapest of its procedures, named in the cell)."""
    out = []
    for case, rows in head.groupby("case", sort=False):
        rows = rows.set_index("solver")
        mine, others = split_smfem(rows)
        reached = next(((t, c) for t in TARGETS if (c := cheapest(mine, f"cpu_s_to_{pct_label(t)}")[1])), None)
        if reached is None:
            out.append((case, None, _pct_text(_best(mine)), ["-" for _ in vs]))
            continue
        target, cost = reached
        cells = [_speedup_cell(others.at[s, f"smfem_speedup_{pct_label(target)}"],
                               engine(s, others.at[s, f"cpu_s_to_{pct_label(target)}"])) if s in others.index else "-"
                 for s, _ in vs]
        out.append((case, target, cost.group(1), cells))
    return out


def summary_table(head: pd.DataFrame, vs=VERSUS) -> list[str]:
    """The verdict as a Markdown table, one row per scene (:func:`scene_rows`)."""
    lines = ["| scene | SMFEM reaches | CPU s | " + " | ".join(f"times faster than {n}" for _, n in vs) + " |",
             "|---|---|---|" + "---|" * len(vs)]
    for case, target, cost, cells in scene_rows(head, vs):
        reached = f"{100 * target:g} %" if target is not None else f"no target (best {cost})"
        lines.append(f"| {case} | {reached} | {cost if target is not None else '-'} | " + " | ".join(cells) + " |")
    return lines
