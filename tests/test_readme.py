"""README's findings as ``python -m reports.readme`` writes them from a published report: every
number in bold is a cell of the verdict table, every scene where SMFEM is slower or misses 1 %
is named, and the blocks between the markers are all it rewrites."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest

from reports.readme import MARKERS, findings, published, scene_prose, written
from reports.verdict import scene_rows, summary_table

QUICK = Path(__file__).resolve().parents[1] / "docs" / "quick-report"


def _leading_numbers(table: list[str]) -> set[str]:
    cells = {c.strip() for line in table[2:] for c in line.split("|")}
    return {m.group(1) for c in cells if (m := re.match(r"^(?:[<>] )?([0-9.]+)", c))}


def _slower_head(head: pd.DataFrame) -> pd.DataFrame:
    """The published table with one scene's 2D speed-up at 1 % made a loss."""
    head = head.copy()
    at = head.index[(head.solver == "reference-2d") & head.smfem_speedup_1pct.astype(str).str.match(r"^[0-9.]+x$")][0]
    head.loc[at, ["smfem_speedup_1pct", "smfem_speedup_1pct_range"]] = "0.5x", "0.45-0.55"
    return head


def test_the_findings_bold_only_the_tables_cells_and_name_every_loss_and_miss():
    head, made = published(QUICK)
    head = _slower_head(head)
    text = findings(head, made)
    assert text.startswith("**What it found**")
    bold = re.findall(r"\*\*([0-9.]+)\*\*", text)
    assert bold and set(bold) <= _leading_numbers(summary_table(head))
    rows = scene_rows(head)
    slower = [case for case, target, _, cells in rows if target == 0.01 and "slower" in cells[0]]
    assert slower and all(f"{scene_prose(case)} (**0.5**)" in text for case in slower)
    for case, target, _, _ in rows:
        if target != 0.01:
            assert scene_prose(case) in text  # at 5 % only, or neither target


def test_a_speed_up_whose_repeats_reach_either_side_of_one_is_as_fast_not_faster():
    """The timing pass's spread decides the word: 1.3 from repeats whose ratios run 0.8-2.6 is the
    host's noise, so the findings say 'as fast', with the spread beside the number."""
    head, made = published(QUICK)
    at = head.index[(head.solver == "reference-2d") & head.smfem_speedup_1pct.astype(str).str.match(r"^[0-9.]+x$")][0]
    case = head.at[at, "case"]
    head.loc[at, ["smfem_speedup_1pct", "smfem_speedup_1pct_range"]] = "1.3x", "0.8-2.6"
    text = findings(head, made)
    assert f"{scene_prose(case)} (**1.3**, its repeats' ratios 0.8-2.6)" in text
    assert "as fast" in text and f"**1.3** times on {scene_prose(case)}" not in text
    head.loc[at, "smfem_speedup_1pct_range"] = "1.1-1.5"
    assert f"{scene_prose(case)} (**1.3**" not in findings(head, made)
    # within half a per cent of one the table says nothing, so neither do the findings
    head.loc[at, ["smfem_speedup_1pct", "smfem_speedup_1pct_range"]] = "0.998x", ""
    text = findings(head, made)
    assert "as fast on " in text  # the clause lists every such scene, in the table's order
    assert f"{scene_prose(case)} (**0.998**)" in text.split("as fast on ", 1)[1].split(". It ")[0]


def test_written_replaces_the_marked_blocks_only_and_refuses_a_readme_without_them():
    head, made = published(QUICK)
    (f0, f1), (v0, v1) = MARKERS["findings"], MARKERS["verdict"]
    readme = f"# smfem\n\nIntro.\n\n{f0}\nold words\n{f1}\n\nBetween.\n\n{v0}\n| old | table |\n{v1}\n\nEnd.\n"
    new = written(readme, head, made)
    assert new.startswith("# smfem\n\nIntro.\n\n") and "\n\nBetween.\n\n" in new and new.endswith("\n\nEnd.\n")
    assert findings(head, made) in new and "\n".join(summary_table(head)) in new and "old" not in new
    assert written(new, head, made) == new
    with pytest.raises(ValueError, match="no block"):
        written("# smfem\n", head, made)
