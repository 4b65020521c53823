"""The quick report as a reader meets it (slow: about 10 minutes with a cold run cache).

Every figure the report draws goes through ``smfem.runs.figures.save``, whose layout check warns;
the test configuration turns that warning into an error, so building the report here checks
every one of its figures: text inside, no two labels overlapping, a unit on every axis.
``SMFEM_REPORT_CACHE`` names a run cache to reuse (default: the report's own, out/report/runs).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from browser import chromium, verdict_on_first_screen
from reports.build import build
from smfem.studies.plan import quick


@pytest.mark.slow
def test_every_figure_of_the_quick_report_reads_cleanly_and_the_verdict_comes_first(tmp_path):
    cache = Path(os.environ.get("SMFEM_REPORT_CACHE", Path(__file__).parents[1] / "out" / "report" / "runs"))
    report = build(quick(), tmp_path / "report", cache=cache, progress=False)
    drawn = sorted((tmp_path / "report" / "figures").glob("*.png"))
    kinds = {p.stem.split("-", 1)[1] for p in drawn}
    assert {"work-precision", "spatial", "histories", "plastic-zones", "field"} <= kinds, kinds
    assert len(drawn) >= 4 * len(report.analyses)
    if chromium():
        top, bottom, dark = verdict_on_first_screen(tmp_path / "report" / "index.html", tmp_path)
        assert 0 <= top and bottom < 995 and dark > 2000, (top, bottom, dark)
