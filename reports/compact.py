"""Tables as a reader pages through them: a sentence in a cell is said once, below the table,
and rows that give the same answer for every solver are one row.

Only the document's tables; ``tables/*.csv`` keep every cell whole.
"""

from __future__ import annotations

import re

import pandas as pd

#: a cell that gives a reason: a short label, a colon, a sentence (``not available: ccx 2.20's
#: implicit dynamics ...``, ``flat: the error is not limited by the step here, ...``); a cost
#: with its settings (``0.0232 (r2 H1 dt2.5e-06)``) has no colon and stays whole
_REASON = re.compile(r"^(?P<label>[^:\n]{2,60}): (?P<why>.{24,})$", re.S)


def footnoted(df: pd.DataFrame) -> tuple[pd.DataFrame, list[str]]:
    """``df`` with each reason cell cut to its label and a note's number (``not available (1)``),
    and the notes: each distinct reason once, numbered in reading order (row by row)."""
    notes: list[str] = []
    for value in df.to_numpy().ravel():  # row by row
        if isinstance(value, str) and value not in notes and _REASON.match(value):
            notes.append(value)

    def cut(value):
        if isinstance(value, str) and value in notes:
            return f"{_REASON.match(value)['label']} ({notes.index(value) + 1})"
        return value

    return df.apply(lambda column: column.map(cut)), notes  # DataFrame.map: pandas 2.1


def merged(df: pd.DataFrame, key: str, groups: list[str], label: str) -> pd.DataFrame:
    """One row for each group (rows equal in ``groups``) whose rows differ in ``key`` alone, with
    ``key`` reading ``label``; the other groups' rows as they are, in the table's order."""
    others = [c for c in df.columns if c != key]
    kept = []
    for _, rows in df.groupby(groups, sort=False, dropna=False):
        same = len(rows) > 1 and (rows[others].nunique(dropna=False) == 1).all()
        kept.append(rows.iloc[:1].assign(**{key: label}) if same else rows)
    return pd.concat(kept) if kept else df
