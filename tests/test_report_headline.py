"""The headline's rows (reports/tables.py): CalculiX's procedures, each a series of its own, share
one row, at each target the cheapest procedure named in its cell, and so do the 3D reference's
implicit and explicit engines; a procedure that cannot take the scene keeps its one line beside
the row."""

from __future__ import annotations

from types import SimpleNamespace

import pandas as pd

from reports.analysis import CaseAnalysis, SolverSummary
from reports.tables import headline_table
from smfem.runs.registry import CALCULIX, CALCULIX_EXPLICIT, CALCULIX_MODAL, REF2D, REF3D, REF3D_EXPLICIT, SMFEM
from smfem.studies import metrics
from smfem.studies.jobs import NOT_AVAILABLE, OK

REFUSED = "calculix (modal): a modal superposition is linear: it takes no plasticity"


def _series(solver: str, *runs) -> SolverSummary:
    """A solver's summary from its runs ``(label, cpu s, total error)``."""
    points = pd.DataFrame([{"label": label, "cpu": cpu, "total": total} for label, cpu, total in runs])
    costs = {t: metrics.cost_to(t, points.cpu, points.total, points.label) for t in metrics.TARGETS}
    return SolverSummary(solver, OK, "", points, [], costs)


def _analysis(case: str, *series: SolverSummary) -> CaseAnalysis:
    truth = SimpleNamespace(name="stored", uncertainty_of=lambda probes: 1e-4)
    return CaseAnalysis(None, SimpleNamespace(name=case, probes=[]), truth, None, pd.DataFrame(),
                        {s.solver: s for s in series}, pd.DataFrame(), pd.DataFrame())


def test_calculix_procedures_share_one_headline_row_at_their_cheapest():
    elastic = _analysis("dome", _series(SMFEM, ("r1", 0.5, 0.03), ("r2", 2.0, 0.008)),
                        _series(REF2D, ("r1", 1.0, 0.02), ("r2", 8.0, 0.006)),
                        _series(CALCULIX, ("r1", 60.0, 0.03)),
                        _series(CALCULIX_EXPLICIT, ("r1", 40.0, 0.04), ("r2", 300.0, 0.012)),
                        _series(CALCULIX_MODAL, ("r1 modes 50", 1.0, 0.04), ("r2 modes 50", 10.0, 0.009)))
    refused = SolverSummary(CALCULIX_MODAL, NOT_AVAILABLE, REFUSED, pd.DataFrame(), [],
                            {t: metrics.cost_to(t, [], [], []) for t in metrics.TARGETS})
    plastic = _analysis("strip", _series(SMFEM, ("r1", 1.0, 0.02)), _series(CALCULIX, ("r1", 50.0, 0.05)),
                        _series(CALCULIX_EXPLICIT, ("r1", 20.0, 0.03)), refused)
    head = headline_table([elastic, plastic]).set_index(["case", "solver"])
    assert list(head.loc["dome"].index) == [SMFEM, REF2D, CALCULIX]
    ccx = head.loc["dome", CALCULIX]
    assert (ccx.cpu_s_to_1pct, ccx.cpu_s_to_5pct) == ("10 (modal r2 modes 50)", "1 (modal r1 modes 50)")
    assert (ccx.smfem_speedup_1pct, ccx.runs, round(ccx.best_error_pct, 9)) == ("5x", 5, 0.9)
    strip = head.loc["strip", CALCULIX]
    assert (strip.cpu_s_to_1pct, strip.cpu_s_to_5pct) == ("not reached (best 3 %, explicit)", "20 (explicit r1)")
    assert plastic.left_out() == [f"CalculiX modal: {REFUSED}"] and elastic.left_out() == []
    from reports.verdict import summary_table  # the README's table: CalculiX's cheapest procedure named

    assert summary_table(head.reset_index())[2:] == ["| dome | 1 % | 2 | 4 | - | 5 (modal) |",
                                                     "| strip | 5 % | 1 | - | - | 20 (explicit) |"]


def test_a_row_of_refused_procedures_says_the_first_reason_and_lists_the_others():
    def no(solver, why):
        return SolverSummary(solver, NOT_AVAILABLE, why, pd.DataFrame(), [],
                             {t: metrics.cost_to(t, [], [], []) for t in metrics.TARGETS})

    contact = _analysis("rod", _series(SMFEM, ("r1", 1.0, 0.005)), no(CALCULIX, "calculix: a rigid wall"),
                        no(CALCULIX_EXPLICIT, "calculix (explicit): contact"),
                        no(CALCULIX_MODAL, "calculix (modal): contact"))
    row = headline_table([contact]).set_index("solver").loc[CALCULIX]
    assert row.cpu_s_to_1pct == "not available: a rigid wall"
    assert contact.left_out() == ["CalculiX explicit: calculix (explicit): contact",
                                  "CalculiX modal: calculix (modal): contact"]


def test_the_3d_row_is_the_cheaper_engine_at_each_target_named_in_its_cell_and_the_verdict():
    """The 3D reference's implicit and explicit engines, each a series of its own, are one row: at
    each target the cheaper engine that reaches it (else the closest), named in the cost cell,
    in the speed-up's verdict sentence and in the summary table's "3D FEM" cell; each engine's
    runs stay its own in the row's points."""
    from reports.verdict import names_an_engine, sentence, summary_table

    analysis = _analysis("thick_cylinder", _series(SMFEM, ("r1", 0.5, 0.03), ("r2", 2.0, 0.008)),
                         _series(REF3D, ("r1", 4.0, 0.04), ("r2", 44.0, 0.011), ("r3", 100.0, 0.009)),
                         _series(REF3D_EXPLICIT, ("r1", 3.0, 0.02), ("r2", 14.0, 0.012), ("r3", 60.0, 0.0095)))
    head = headline_table([analysis])
    row = head.set_index("solver").loc[REF3D]
    assert list(head.solver) == [SMFEM, REF3D]
    assert (row.cpu_s_to_1pct, row.cpu_s_to_5pct) == ("60 (explicit r3)", "3 (explicit r1)")
    assert (row.smfem_speedup_1pct, row.smfem_speedup_5pct, row.runs) == ("30x", "6x", 6)
    assert sentence("thick_cylinder", head.set_index("solver")).endswith(
        ": 30 times faster than the 3D reference (explicit).")
    assert summary_table(head)[2] == "| thick_cylinder | 1 % | 2 | - | 30 (explicit) | - |"
    from smfem.cli.study import headline_lines

    assert headline_lines(head)[0].endswith("; speed-up over reference-3d 30x (explicit)")
    # the implicit engine cheaper at 1 %, neither engine within 0.5 %: the closest named
    implicit = _analysis("dome", _series(SMFEM, ("r1", 0.5, 0.03), ("r2", 2.0, 0.008)),
                         _series(REF3D, ("r2", 40.0, 0.009)), _series(REF3D_EXPLICIT, ("r2", 300.0, 0.0095)))
    cells = headline_table([implicit]).set_index("solver").loc[REF3D]
    assert cells.cpu_s_to_1pct == "40 (implicit r2)" and cells.smfem_speedup_1pct == "20x"
    assert summary_table(headline_table([implicit]))[2] == "| dome | 1 % | 2 | - | 20 (implicit) | - |"
    assert names_an_engine(head, REF3D) and not names_an_engine(head, SMFEM)
    # a table written before the explicit engine (no engine in its cells) reads as it did
    old = head.assign(cpu_s_to_1pct="98.6 (r3 dt2.5e-06)", cpu_s_to_5pct="4.49 (r1 dt1e-05)")
    assert summary_table(old)[2].endswith("| 30 | - |") and not names_an_engine(old, REF3D)


def test_an_engine_that_cannot_take_a_scene_keeps_its_line_beside_the_3d_row():
    refused = SolverSummary(REF3D_EXPLICIT, NOT_AVAILABLE, "explicit reference: a wall with friction is not available "
                            "(frictionless only)", pd.DataFrame(), [],
                            {t: metrics.cost_to(t, [], [], []) for t in metrics.TARGETS})
    wall = _analysis("rod", _series(SMFEM, ("r1", 1.0, 0.005)), _series(REF3D, ("r1", 20.0, 0.006)), refused)
    row = headline_table([wall]).set_index("solver").loc[REF3D]
    assert row.cpu_s_to_1pct == "20 (implicit r1)"
    assert wall.left_out() == ["reference FEM 3D, explicit: explicit reference: a wall with friction is not "
                               "available (frictionless only)"]
