"""The solver table (:mod:`smfem.runs.registry`) is the one place a solver is declared: a toy solver
registered there is offered by the command line and runs through a study into its tables and
figures; the built-in entries keep the report's styles and tell the truth about what they
refuse."""

from __future__ import annotations

import json
from dataclasses import replace
from types import SimpleNamespace

import pandas as pd
import pytest

from cases import ParameterError, UnsupportedCase, get_case, rebuild
from smfem.cli import main
from reports import figures
from reports.build import build
from smfem.studies.plan import MODAL_TRUTH, REF2D, SMFEM, CaseStudy, Series, TruthPlan
import smfem.runs.figures
from smfem.runs import registry
from smfem.runs.registry import (CALCULIX, CALCULIX_EXPLICIT, CALCULIX_MODAL, CONTACT, EXPLICIT, PLASTICITY, REF3D,
                                 REF3D_EXPLICIT, REFERENCE, SMFEM_QUAD9, Solver, lookup, solvers)

COARSE = "reference-coarse"


def reference_at_refine_1(case, **how):
    """The toy solver: the reference FEM on the paper mesh whatever ``refine`` the case asks for
    (module level: a study's worker processes import it by name)."""
    return registry.solve(REFERENCE, rebuild(case, {"refine": 1}), **how)


@pytest.fixture
def coarse():
    """The toy solver in the table for one test, and out of it afterwards."""
    entry = registry.register(Solver(COARSE, reference_at_refine_1, family=REFERENCE, dim=2,
                                     label="reference FEM, paper mesh", color="C9", marker="*"))
    yield entry
    registry.unregister(COARSE)


def test_a_registered_solver_is_offered_by_smfem_run_and_runs(coarse, tmp_path):
    out = tmp_path / "run"
    assert main(["run", "dome", "--solver", COARSE, "--out", str(out), "--quiet", "--set", "t_end=4e-5"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["solver"] == REFERENCE and summary["converged"]


def test_a_registered_solver_runs_through_a_study_into_its_tables_and_figures(coarse, tmp_path, monkeypatch):
    study = (CaseStudy("dome", (Series(SMFEM, ({},)), Series(COARSE, ({},))), reference=(REF2D, {"refine": 2}),
                       truth=TruthPlan(MODAL_TRUTH, refine=(1, 2)), base={"t_end": 4e-5}),)
    report = build(study, tmp_path / "report", workers=2, progress=False, settings="tiny", document=False)
    for table in ("runs", "errors", "headline"):
        rows = pd.read_csv(tmp_path / "report" / "tables" / f"{table}.csv")
        assert (rows.solver == COARSE).any(), table
    runs = pd.read_csv(tmp_path / "report" / "tables" / "runs.csv")
    assert (runs[runs.solver == COARSE].status == "ok").all()
    assert (tmp_path / "report" / "figures" / "dome-work-precision.png").exists()
    kept = []
    monkeypatch.setattr(smfem.runs.figures, "close", kept.append)
    figures.work_precision(report.analyses[0], tmp_path / "wp.png")
    front = [line for ax in kept[0].axes for line in ax.get_lines() if line.get_label() == f"{coarse.label} (front)"]
    assert len(front) == 1 and (front[0].get_color(), front[0].get_marker()) == (coarse.color, coarse.marker)


def test_the_toy_solver_is_gone_after_its_test():
    assert COARSE not in [s.name for s in solvers()]
    with pytest.raises(ValueError, match=f"unknown solver '{COARSE}': choose one of smfem, smfem-quad9, reference"):
        lookup(COARSE)
    with pytest.raises(ValueError, match="unknown solver"):
        Series(COARSE, ({},))


def test_smfem_with_the_quadratic_element_is_a_series_of_its_own():
    """The quadratic element's entry fixes the case's element as the 3-D reference fixes dim:
    in the job's parameters (so its cached runs and records say so), in the case it runs, and
    as the entry a quad9 case is named by (``smfem run --tol`` reads its front)."""
    from smfem.studies.jobs import Job

    job = Job.make("dome", SMFEM_QUAD9, {"refine": 2})
    assert dict(job.overrides) == {"refine": 2, "element": "quad9"}
    assert job.resolved.params["element"] == "quad9"
    assert registry.with_fixed(SMFEM_QUAD9, get_case("dome")).params["element"] == "quad9"
    assert registry.named_for(SMFEM, get_case("dome", {"element": "quad9"})) == SMFEM_QUAD9
    assert registry.named_for(SMFEM, get_case("dome")) == SMFEM
    assert registry.named_for(REFERENCE, get_case("dome", {"dim": 3})) == REF3D
    assert lookup(SMFEM_QUAD9).family == SMFEM and Job.make("dome", SMFEM, {}).overrides == ()


def test_a_name_is_registered_once():
    with pytest.raises(ValueError, match="registered already"):
        registry.register(Solver(SMFEM, reference_at_refine_1))


def test_the_table_keeps_the_reports_styles_labels_and_choices():
    """Today's figures: the four solvers of a study drawn as before the table."""
    drawn = {s.name: (s.color, s.marker, s.label) for s in solvers() if s.series}
    assert drawn == {SMFEM: ("C0", "o", "SMFEM"), SMFEM_QUAD9: ("C3", "*", "SMFEM quad9"), REF2D: ("C1", "s", "reference FEM 2D"),
                     REF3D: ("C2", "^", "reference FEM 3D"), REF3D_EXPLICIT: ("C2", "<", "reference FEM 3D, explicit"),
                     CALCULIX: ("C4", "D", "CalculiX"), CALCULIX_EXPLICIT: ("C4", ">", "CalculiX explicit"),
                     CALCULIX_MODAL: ("C4", "d", "CalculiX modal")}
    assert [s.name for s in solvers() if s.command_line] == [SMFEM, REFERENCE, CALCULIX, "reference-explicit"]
    assert {s.name: s.dim for s in solvers() if s.dim} == {REF2D: 2, REF3D: 3, REF3D_EXPLICIT: 3}


@pytest.mark.parametrize("feature,case", [(PLASTICITY, ("dome", {"plastic": True})), (CONTACT, ("rod_impact", {}))])
def test_a_solver_without_a_feature_refuses_a_case_that_needs_it(feature, case, monkeypatch):
    """The table's word against the solvers' own refusals (CalculiX refuses before it would
    start ccx, so it need not be installed)."""
    import reference_fem.calculix.solver

    monkeypatch.setattr(reference_fem.calculix.solver, "find_ccx", lambda: "ccx")
    lacking = [s for s in solvers() if feature not in s.supports]
    assert lacking
    for entry in lacking:
        with pytest.raises(UnsupportedCase):
            registry.solve(entry.name, get_case(*case))


def test_calculix_procedures_are_series_of_their_own_in_one_headline_row():
    """An entry that fixes a solver option (CalculiX's procedure) is a series of its own, the
    option added to every run and a clash refused in one line; its headline row is its family's,
    its cells named by its variant; a level's option (``modes``) is the run's, not the case's."""
    from smfem.studies.jobs import Job

    seen = {}

    def run(case, **how):  # what ccx would be handed
        seen.update(how["options"])
        return SimpleNamespace(mesh=None)

    modal = lookup(CALCULIX_MODAL)
    registry.solve(replace(modal, run=run), get_case("dome"), options={"modes": 50})
    assert seen == {"modes": 50, "procedure": "modal"}
    with pytest.raises(ParameterError, match="calculix-modal runs with procedure=modal, not procedure=explicit"):
        registry.solve(modal, get_case("dome"), options={"procedure": "explicit"})
    assert {s.name: s.variant for s in solvers() if s.family == CALCULIX} == {
        CALCULIX: "implicit", CALCULIX_EXPLICIT: "explicit", CALCULIX_MODAL: "modal"}
    assert [registry.headline_name(s) for s in (CALCULIX, CALCULIX_EXPLICIT, CALCULIX_MODAL, SMFEM_QUAD9, REF3D)] == [
        CALCULIX, CALCULIX, CALCULIX, SMFEM_QUAD9, REF3D]
    assert [registry.headline_name(s) for s in (REF2D, REF3D_EXPLICIT, EXPLICIT)] == [REF2D, REF3D, EXPLICIT]
    assert registry.split_level(CALCULIX_MODAL, {"refine": 2, "modes": 50}) == ({"refine": 2}, {"modes": 50})
    gauss = {"refine": 2, "time_scheme": "gauss"}  # a case parameter, though SMFEM's alone
    assert registry.split_level("smfem", gauss) == (gauss, {})
    assert Job.make("dome", CALCULIX_MODAL, {"refine": 2}).overrides == (("refine", 2),)  # the name says the procedure


def test_the_explicit_3d_reference_is_the_explicit_engine_at_dim_3_in_the_3d_row(monkeypatch):
    """``reference-3d-explicit`` runs the explicit reference with ``dim`` 3 (its runs' family, and
    the entry ``reference-explicit`` at dim 3 is named by), in the headline's 3D row where the
    cells name the engine; its step is its own Courant limit, so its ladder predicts one more
    power of the mesh; it refuses what the engine cannot take in one line, before any work."""
    import reference_fem.explicit

    entry = lookup(REF3D_EXPLICIT)
    assert (entry.family, entry.fixed, entry.headline, entry.variant, lookup(REF3D).variant) == (
        EXPLICIT, {"dim": 3}, REF3D, "explicit", "implicit")
    assert entry.series and entry.dear and entry.courant and not lookup(REF3D).courant
    assert entry.packages == ("reference_fem",) and entry.options() == lookup(EXPLICIT).options()
    assert registry.named_for(EXPLICIT, get_case("rod_impact", {"dim": 3})) == REF3D_EXPLICIT
    seen = {}

    def explicit(case, **how):  # what the engine is handed
        seen.update(dim=case.params["dim"], **how)
        return SimpleNamespace(mesh=None)

    monkeypatch.setattr(reference_fem.explicit, "solve", explicit)
    registry.solve(REF3D_EXPLICIT, get_case("thick_cylinder"), options={"bbar": True})
    assert seen["dim"] == 3 and seen["bbar"] is True
    monkeypatch.undo()
    with pytest.raises(UnsupportedCase, match="^explicit reference: contact with plasticity is not available$"):
        registry.solve(REF3D_EXPLICIT, get_case("rod_impact", {"plastic": True, "refine": 1, "t_end": 1e-6}))
