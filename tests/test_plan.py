"""The plans (smfem/studies/plan.py): CalculiX's procedures in the full plan where each takes the
scene, refused in one run where it cannot; the quick plan's light CalculiX series only where ccx
is installed; the explicit 3D reference in the full plan wherever it takes a scene."""

from __future__ import annotations

import shutil

import pytest

from cases import ParameterError, UnsupportedCase, get_case
from reference_fem.calculix.procedures import refuse
from reference_fem.explicit import refuse as explicit_refuse
from smfem.runs.registry import CALCULIX, CALCULIX_EXPLICIT, CALCULIX_MODAL, REF3D, REF3D_EXPLICIT, lookup
from smfem.studies.plan import CCX_EXPLICIT, CCX_UNTIL, CCX_MODAL, EXPLICIT_3D, FULL_UNTIL, full, quick
from smfem.studies.study import job_of

PROCEDURES = {CALCULIX_EXPLICIT: "explicit", CALCULIX_MODAL: "modal"}


def _takes(case: str, procedure: str) -> bool:
    try:
        refuse(get_case(case), procedure, None)
    except UnsupportedCase:
        return False
    return True


def test_the_full_plan_carries_each_procedure_that_takes_a_scene_and_keeps_the_refusal_of_the_others():
    with_ccx = [study for study in full() if any(s.solver == CALCULIX for s in study.series)]
    assert {study.case for study in with_ccx} >= {"dome", "thick_cylinder", "notched_strip", "layered_cylinder",
                                                  "layered_cylinder_pulse", "moving_load", "notched_cylinder"}
    for study in with_ccx:
        series = {s.solver: s for s in study.series}
        for solver, procedure in PROCEDURES.items():
            s = series[solver]
            if _takes(study.case, procedure):
                # within CCX_UNTIL's budget: ccx's explicit increment follows the mesh, and its 1 %
                # takes r3 or r4 on the cylinders; modal's, 800 modes on the finer mesh
                assert s.until == CCX_UNTIL, (study.case, solver)
                assert s.until.target == FULL_UNTIL.target and s.until.budget_s >= FULL_UNTIL.budget_s
                assert s.levels == (CCX_MODAL if procedure == "modal" else CCX_EXPLICIT)
            else:  # one run, refused in the solver's one line before ccx starts
                assert s.levels == ({},) and s.until is None, (study.case, solver)
        modal = [job_of(study)(CALCULIX_MODAL, level) for level in series[CALCULIX_MODAL].levels]
        assert all(dict(job.options).keys() <= {"modes"} and "modes" not in dict(job.overrides) for job in modal)


@pytest.mark.parametrize("found", [True, False])
def test_the_quick_plan_has_a_light_calculix_series_only_where_ccx_is_found(found, monkeypatch):
    if found and shutil.which("ccx") is None:
        pytest.skip("ccx (CalculiX) is not installed")
    if not found:
        monkeypatch.setenv("SMFEM_CCX", "no-such-ccx-here")
    assert lookup(CALCULIX_MODAL).installed() == found
    light = {study.case: s.levels for study in quick() for s in study.series if s.solver == CALCULIX_MODAL}
    # two levels of the cheapest procedure, modal (benchmarks/README.md), on the scenes where ccx is cheap
    two = ({"modes": 50}, {"modes": 100})
    assert light == ({"dome": ({"refine": 1, "modes": 50}, {"refine": 2, "modes": 50}), "thick_cylinder": two,
                      "layered_cylinder_pulse": two, "moving_load": two} if found else {})
    assert not any(s.solver == CALCULIX_EXPLICIT for study in quick() for s in study.series)


def test_a_study_of_some_solvers_keeps_only_their_series_and_refuses_an_unknown_one(tmp_path, capsys):
    from smfem.cli import main
    from smfem.studies.plan import full, with_solvers

    plan = full()
    kept = with_solvers(plan, ("smfem", "reference-2d"))
    assert with_solvers(plan, ()) is plan
    assert {s.solver for study in kept for s in study.series} == {"smfem", "reference-2d"}
    assert [study.case for study in kept] == [study.case for study in plan]
    dome = next(s for s in kept if s.case == "dome")
    assert dome.reference[0] == "reference-2d" and set(dome.estimated) <= {"smfem", "reference-2d"}
    assert all(s.reference is None for s in with_solvers(plan, ("smfem",)))
    with pytest.raises(ParameterError, match="no series of solver 'reference-4d'"):
        with_solvers(plan, ("smfem", "reference-4d"))
    assert main(["study", "dome", "--solvers", "nonsense", "--out", str(tmp_path / "s"), "--quiet"]) == 2
    assert "no series of solver 'nonsense'" in capsys.readouterr().err and not (tmp_path / "s").exists()


def _explicit_takes(case: str) -> bool:
    try:
        explicit_refuse(get_case(case, {"dim": 3}))
    except UnsupportedCase:
        return False
    return True


def test_the_full_plan_carries_the_explicit_3d_engine_on_every_scene_it_takes_and_says_why_not_elsewhere():
    """A series of the explicit 3D reference over meshes, carried like every other, on each scene
    of the full plan the engine takes; where it has none, the scene says why in one line (its
    first run past the budget or the machine); never in the quick plan (its 10 minutes)."""
    plan = full()
    explicit = {study.case: s for study in plan for s in study.series if s.solver == REF3D_EXPLICIT}
    left_out = {study.case: dict(study.left_out) for study in plan}
    assert set(explicit) >= {"dome", "thick_cylinder", "notched_cylinder", "notched_strip", "rod_impact",
                             "ring_in_ring", "layered_cylinder", "layered_cylinder_pulse", "moving_load",
                             "moving_load_notched"}
    for study in plan:
        said = left_out[study.case].get(REF3D_EXPLICIT) or left_out[study.case].get(REF3D)
        if study.case in explicit:
            s = explicit[study.case]
            assert _explicit_takes(study.case) and not said, study.case
            assert s.levels == EXPLICIT_3D and s.until == FULL_UNTIL
            # the notched scenes' element is B-bar, as their truths' and the implicit 3D notched cylinder's
            assert dict(s.options) == ({"bbar": True} if "notched" in study.case else {}), study.case
        else:  # a scene the engine takes (nothing in the full plan is refused) but too dear here: one line why
            assert said and "\n" not in said and len(said) < 200, study.case
    assert set(explicit) | {c for c, why in left_out.items() if why} == {study.case for study in plan}
    assert not any(s.solver == REF3D_EXPLICIT for study in quick() for s in study.series)


def _normal(case: str, level: dict) -> tuple:
    return tuple(sorted({"refine": 1, "dt": get_case(case).dt, **level}.items()))


def test_the_full_plan_holds_every_level_of_the_quick_plan_once():
    """A ladder runs its levels cheapest first: a level the quick study has is never missing from
    the full one's series of the same solver and options (the quick 3D dome at twice the step
    reached 5 % in 2.9 CPU s, the full ladder's cheapest was 148 s), and no run is asked twice."""
    from smfem.studies.plan import _quick_studies

    full_of = {s.case: s for s in full()}
    compared = 0
    for q in _quick_studies():
        for series in q.series:
            mine = [s for s in full_of[q.case].series if (s.solver, s.options) == (series.solver, series.options)]
            if not mine or len(mine[0].levels) < 2:  # another element (the notched cylinder's B-bar), or one run
                continue
            have = {_normal(q.case, level) for level in mine[0].levels}
            assert {_normal(q.case, level) for level in series.levels} <= have, (q.case, series.solver)
            compared += 1
    assert compared >= 30
    for study in full():
        for s in study.series:
            normal = [_normal(study.case, level) for level in s.levels]
            assert len(normal) == len(set(normal)), (study.case, s.solver)


def test_each_time_stepping_ladder_of_the_full_plan_tries_twice_its_longest_step():
    """Each space level of a series over the time step also runs at twice the longest step the
    plan gave it, unless the solver steps at its own Courant limit (explicit engines: ``dt`` is
    their output interval) or the series spans no step (CalculiX's modal ladder)."""
    from smfem.studies.plan import _full_studies

    full_of = {s.case: {(x.solver, x.options): x for x in s.series} for s in full()}
    longer = 0
    for study in _full_studies():
        for s in study.series:
            have = {_normal(study.case, level) for level in full_of[study.case][(s.solver, s.options)].levels}
            spans = len(s.levels) > 1 and any("dt" in level for level in s.levels)
            longest = {}
            for level in s.levels:
                normal = dict(_normal(study.case, level))
                key = tuple(sorted((k, v) for k, v in normal.items() if k != "dt"))
                longest[key] = max(longest.get(key, 0.0), normal["dt"])
            for key, dt in longest.items():
                doubled = _normal(study.case, {**dict(key), "dt": 2 * dt})
                if spans and not lookup(s.solver).courant:
                    assert doubled in have, (study.case, s.solver, key)
                    longer += 1
                elif lookup(s.solver).courant:
                    assert doubled not in have, (study.case, s.solver, key)
    assert longer >= 100
    # the moving load's 2D reference, at twice its case's step, where the quick study reaches 1 %
    assert _normal("moving_load", {"dt": 2 * get_case("moving_load").dt}) in {
        _normal("moving_load", level) for level in full_of["moving_load"][("reference-2d", ())].levels}
