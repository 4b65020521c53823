"""The report's stability section: the figures of :mod:`reports.stability_study`.

The table takes about a minute, so it is cached beside the runs, by the code version of both
solvers; a tiny (test) study leaves the section out.
"""

from __future__ import annotations

import pandas as pd

from smfem.studies.cache import code_version
from smfem.studies.plan import REFERENCE, SMFEM
from .blocks import Section, items, p, table

#: studies that carry the section (the tests' tiny study does not)
WITH_STABILITY = ("quick", "full")


def stability_rows(cache_dir) -> pd.DataFrame:
    path = cache_dir / f"stability-{code_version(SMFEM)}-{code_version(REFERENCE)}.csv"
    if not path.exists():
        from .stability_study import stability_table

        cache_dir.mkdir(parents=True, exist_ok=True)
        pd.DataFrame(stability_table()).to_csv(path, index=False)
    return pd.read_csv(path)


def stability(ctx) -> list[Section]:
    if ctx.settings not in WITH_STABILITY:
        return []
    rows = stability_rows(ctx.out / "runs")
    rows.to_csv(ctx.out / "tables" / "stability.csv", index=False)
    failed = rows[~rows.passed]
    return [Section("stability", "Stability on stiff and extreme settings", [
        p("Each row is one figure of reports/stability_study.py, with its acceptance limit; tests/test_stability.py "
          "and tests/test_bad_input.py assert the same figures."),
        items([
            "unconditional stability: linear free vibration, dt at 1, 10 and 100 times the explicit limit "
            "2 / omega_max, energy drift over 10^4 steps;",
            "near incompressibility: Lame under internal pressure at nu = 0.49 ... 0.4999;",
            "thin dome: R/h from 54 to 1000, SMFEM 4 x 20, the mesh with 3 elements per clamped-edge layer and "
            "the quadratic element (quad9) on 4 x 20;",
            "200 harmonics; cut-out contrast 1e-2 ... 1e-10; rod impact at 100 v0 with friction 0 ... 1;",
            "bad input: every out-of-range value of every key and every solver option through the command line.",
        ]),
        p(f"{len(rows) - len(failed)} of {len(rows)} figures within their limits."
          + ("" if failed.empty else " Outside: " + "; ".join(f"{r.check}, {r.setting}" for r in failed.itertuples())
             + " (the thin dome at 4 x 20 cannot resolve the clamped edge's bending layer beyond R/h = 150).")),
    ], appendix=[table(rows)])]

