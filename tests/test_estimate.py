"""Every run's error estimate from cheap companions (smfem.runs.estimate)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from cases import get_case
from smfem.cli import main
from smfem.runs import estimate as E
from smfem.runs.registry import CALCULIX, MODAL, REF2D, SMFEM

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def test_the_companions_of_each_kind_of_run():
    parts = lambda case, solver: {c.name: c.overrides for c in E.companions(case, solver)}
    tc = get_case("thick_cylinder")
    assert parts(tc, SMFEM) == {"space": {"coarsen": 2}, "time": {"coarsen": 2, "dt": 2 * tc.dt},
                                "time2": {"coarsen": 2, "dt": 4 * tc.dt},
                                "harmonics": {"coarsen": 2, "harmonics": tc.harmonics // 2},
                                "harmonics2": {"coarsen": 2, "harmonics": tc.harmonics // 4}}
    assert parts(get_case("thick_cylinder", {"refine": 4}), SMFEM)["space"] == {"refine": 2}
    assert "harmonics" not in parts(get_case("dome"), SMFEM)  # axisymmetric: one harmonic, exact
    assert set(parts(tc, REF2D)) == {"space", "time", "time2"}  # no harmonics in a full 2D model
    # half the strip's mesh keeps its notch: the notch edge stays a node (2 + 8 elements, not 10)
    strip, coarse = get_case("notched_strip"), get_case("notched_strip", {"coarsen": 2})
    grid = coarse.section.t.grid(coarse.mesh_scale, coarse.cutout_edges[1])
    assert len(grid) == 11 and np.isclose(grid, strip.params["notch_depth"]).any()
    assert np.allclose(strip.section.t.grid(2, strip.cutout_edges[1]), strip.section.t.grid(2))  # same mesh where on the grid
    assert parts(tc, CALCULIX) == {} and parts(tc, MODAL) == {}


def test_coarsen_halves_the_paper_mesh():
    tc, coarse = get_case("thick_cylinder"), get_case("thick_cylinder", {"coarsen": 2})
    n = lambda c: len(c.section.s.grid(c.mesh_scale)) - 1
    assert n(tc) == 2 * n(coarse) or n(tc) == 2 * n(coarse) - 1
    assert E.space_ratio(tc, coarse) == pytest.approx(n(tc) / n(coarse))
    with pytest.raises(Exception, match="coarsen"):
        get_case("thick_cylinder", {"coarsen": 0})


def _fake_solver(a=0.3, b=2e5, c=4.0, time_order=2):
    """A 'solver' whose error is known: a/N^2 in space (N: the section's elements along its
    refinable axis), b dt^time_order in time, c/H^2 in the harmonics."""
    def run(solver, case):
        n = len(case.section.s.grid(case.mesh_scale)) - 1
        t = np.arange(0.0, 1e-3 + case.dt / 2, case.dt)
        err = a / n ** 2 + b * case.dt ** time_order + c / case.harmonics ** 2
        hist = {p.name: np.sin(2e3 * t) * (1 + err) for p in case.probes}
        return SimpleNamespace(t=t, history=hist, cpu_time_s=0.01, converged=True, message="")
    return run, (lambda case: a / (len(case.section.s.grid(case.mesh_scale)) - 1) ** 2), \
        (lambda case: b * case.dt ** time_order), (lambda case: c / case.harmonics ** 2)


def test_each_part_is_recovered_when_the_orders_hold():
    run, space, time, harmonics = _fake_solver()
    case = get_case("thick_cylinder", {"refine": 2, "dt": 1e-5, "t_end": 1e-3})
    est = E.estimate(case, SMFEM, run(SMFEM, case), run=run)
    coarse = get_case("thick_cylinder", {"refine": 1, "dt": 1e-5, "t_end": 1e-3})
    for probe, parts in est["probes"].items():
        # the relative max-norm of (1 + e_f) - (1 + e_c) over 1 + e_f: within the e's own size
        assert parts["space"] == pytest.approx(space(case), rel=0.1)
        assert parts["time"] == pytest.approx(time(coarse), rel=0.1)  # measured on the coarse mesh
        assert parts["harmonics"] == pytest.approx(harmonics(coarse), rel=0.1)
        assert parts["total"] == pytest.approx(parts["space"] + parts["time"] + parts["harmonics"])
        assert parts["orders"] == pytest.approx({"space": 2.0, "time": 2.0, "harmonics": 2.0}, rel=0.05)  # observed
    assert est["companions_cpu_total_s"] == pytest.approx(0.05)


def test_a_gauss_runs_time_part_is_read_at_the_schemes_order_4():
    """time_scheme=gauss: the observed time order may reach 4 (Newmark's is kept within 2)."""
    run, _, time, _ = _fake_solver(b=1e16, time_order=4)
    settings = {"refine": 2, "dt": 1e-5, "t_end": 1e-3}
    gauss = get_case("thick_cylinder", {**settings, "time_scheme": "gauss"})
    est = E.estimate(gauss, SMFEM, run(SMFEM, gauss), run=run)
    coarse = get_case("thick_cylinder", {**settings, "refine": 1})
    for parts in est["probes"].values():
        assert parts["orders"]["time"] == pytest.approx(4.0, rel=0.05)
        assert parts["time"] == pytest.approx(time(coarse), rel=0.1)
    assert E.order(gauss, "time") == 4.0 and E.order(coarse, "time") == 2.0


def test_smfem_run_writes_its_estimate_and_prints_one_line(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", "thick_cylinder", "--out", str(out), "--quiet", "--no-fields"]) == 0
    printed = capsys.readouterr().out.splitlines()
    est = json.loads((out / "summary.json").read_text())["error_estimate"]
    assert est["method"] == "companions" and set(est["probes"]) == {"A_ur", "B_ut", "C_ur"}
    assert all(math.isfinite(v["total"]) and v["total"] > 0 for v in est["probes"].values())
    assert len(printed) == 2 and printed[1].startswith("thick_cylinder (smfem): estimated error ")
    assert "space" in printed[1] and "time" in printed[1] and "harmonics" in printed[1]
    assert main(["run", "thick_cylinder", "--out", str(tmp_path / "off"), "--quiet", "--no-fields",
                 "--estimate", "off"]) == 0
    assert "error_estimate" not in json.loads((tmp_path / "off" / "summary.json").read_text())


def test_a_scene_file_gets_an_estimate(tmp_path, capsys):
    scene = tmp_path / "strip.toml"
    text = (EXAMPLES / "notched_strip.toml").read_text()
    scene.write_text(text.replace("notch_depth = 0.025", "notch_depth = 0.015").replace("harmonics = 120", "harmonics = 40")
                     .replace("t_end = 3.2e-4", "t_end = 6.4e-5"))
    assert main(["run", str(scene), "--out", str(tmp_path / "run"), "--quiet", "--no-fields"]) == 0
    est = json.loads((tmp_path / "run" / "summary.json").read_text())["error_estimate"]
    assert {"space", "time", "harmonics"} <= set(est["companions"]) and est["probes"]["mid_uz"]["total"] > 0
    assert "estimated error" in capsys.readouterr().out


def test_no_accuracy_is_claimed_outside_the_model(tmp_path):
    assert main(["run", "thick_cylinder", "--set", "plastic=true", "--set", "q=5e8", "--out", str(tmp_path),
                 "--quiet"]) == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert not summary["validity"]["valid"] and summary["error_estimate"]["claim"].startswith("none")


def test_tol_refines_until_the_estimate_meets_the_target(tmp_path, capsys):
    out = tmp_path / "tol"
    args = ["run", "thick_cylinder", "--set", "t_end=1.6e-3", "--tol", "5%", "--out", str(out), "--quiet", "--no-fields"]
    assert main(args) == 0
    summary = json.loads((out / "summary.json").read_text())
    tol = summary["tolerance"]
    assert tol["met"] and tol["target"] == 0.05 and len(tol["runs"]) >= 2  # the case's settings do not reach 5 %
    assert tol["runs"][-1]["estimate"] <= 0.05 < tol["runs"][0]["estimate"]
    assert max(v["total"] for k, v in summary["error_estimate"]["probes"].items()) <= 0.05
    assert "--tol 5 % met" in capsys.readouterr().out.splitlines()[-1]


def test_tol_says_in_one_line_when_the_budget_is_too_small(tmp_path, capsys):
    out = tmp_path / "tol"
    assert main(["run", "thick_cylinder", "--set", "t_end=1.6e-3", "--tol", "0.5%", "--max-cpu", "0.05",
                 "--out", str(out), "--quiet", "--no-fields"]) == 3
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1 and "not met within --max-cpu" in err[0] and (out / "summary.json").exists()


@pytest.mark.parametrize("tol, words", [("0.01%", "below three times"), ("abc", "give a relative accuracy"),
                                        ("150%", "between 0 and 100")])
def test_tol_refuses_what_cannot_be_shown_or_read(tmp_path, capsys, tol, words):
    assert main(["run", "thick_cylinder", "--tol", tol, "--out", str(tmp_path / "x"), "--quiet"]) == 2
    assert words in capsys.readouterr().err
    assert not (tmp_path / "x" / "summary.json").exists()


def test_a_part_whose_coarser_companions_do_not_converge_is_measured_upward():
    """Harmonics with a cliff (a notch not represented below 15 terms): the run's 20 converge,
    its companions' 10 and 5 do not; the part comes from 30 terms instead, within [0.8, 3]."""
    def run(solver, case):
        n = len(case.section.s.grid(case.mesh_scale)) - 1
        t = np.arange(0.0, 1e-3 + case.dt / 2, case.dt)
        h = 4.0 / case.harmonics ** 2 if case.harmonics >= 15 else 0.5
        err = 0.3 / n ** 2 + 2e5 * case.dt ** 2 + h
        return SimpleNamespace(t=t, history={p.name: np.sin(2e3 * t) * (1 + err) for p in case.probes},
                               cpu_time_s=0.01, converged=True, message="")
    case = get_case("thick_cylinder", {"dt": 1e-5, "t_end": 1e-3})
    est = E.estimate(case, SMFEM, run(SMFEM, case), run=run)
    assert est["measured_upward"] == ["harmonics"] and est["companions"]["harmonics_up"]["harmonics"] == 30
    actual = 4.0 / 20 ** 2
    for parts in est["probes"].values():
        assert 0.8 < parts["harmonics"] / actual < 3 and parts["orders"]["harmonics"] == E.ORDERS["harmonics"]


def test_the_difference_of_histories_too_small_to_square_is_still_measured():
    """Displacements of 1e-200 (a valid but extreme scene) underflow when squared: the max-norm
    is still measured, the L2 norm is NaN, and no warning is raised."""
    import warnings

    from smfem.runs.errors import history_errors

    t = np.linspace(0.0, 1.0, 11)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        e_max, e_l2 = history_errors(t, 1.1e-200 * np.sin(t), t, 1e-200 * np.sin(t))
    assert e_max == pytest.approx(0.1) and math.isnan(e_l2)


def test_tol_starts_from_the_stored_front_and_its_measured_error_holds(tmp_path, capsys):
    """On a built-in scene the first run is the stored front's cheapest setting within the
    target, and the error the front measured there is the run's: recomputed against the stored
    truth, it is the same."""
    from smfem.studies.metrics import history_errors
    from smfem.studies.stored import directory, read, read_front

    front = read_front("thick_cylinder")
    within = front[(front.solver == SMFEM) & (front.total <= 0.05)].sort_values("cpu_s").iloc[0]
    out = tmp_path / "tol"
    assert main(["run", "thick_cylinder", "--tol", "5%", "--out", str(out), "--quiet", "--no-fields"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "measured front" in lines[0] and "--tol 5 % met: measured" in lines[-1]
    summary = json.loads((out / "summary.json").read_text())
    tol = summary["tolerance"]
    assert tol["met"] and len(tol["runs"]) == 1
    run = tol["runs"][0]
    assert run["settings"]["dt"] == pytest.approx(within["dt"]) and run["settings"]["harmonics"] == within.harmonics
    assert run["measured_against_truth"] == pytest.approx(within.total)
    case, truth = get_case("thick_cylinder"), read(directory("thick_cylinder"))
    history = pd.read_csv(out / "history.csv")
    window = case.references.get("comparison_window_s", 0.0)
    actual = max(history_errors(history.t.to_numpy(), history[p.name].to_numpy(), truth.t, truth.values[p.name],
                                window)[0] for p in case.probes if p.field in ("u", "v"))
    assert actual == pytest.approx(within.total, rel=1e-3) and actual <= 0.05


def test_tol_without_the_estimate_is_the_fronts_cheapest_run_alone(tmp_path, capsys):
    """``--estimate off``: the stored front's setting within the target, run alone (no
    companions), its measured error standing for the run's; where no front reaches the target
    (here: another load), a user mistake."""
    out = tmp_path / "tol"
    assert main(["run", "thick_cylinder", "--tol", "5%", "--estimate", "off", "--out", str(out), "--quiet",
                 "--no-fields"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert "error_estimate" not in summary and summary["tolerance"]["met"]
    run = summary["tolerance"]["runs"][0]
    assert run["estimate"] is None and run["measured_against_truth"] <= 0.05 and run["cpu_s"] == summary["cpu_time_s"]
    assert main(["run", "thick_cylinder", "--set", "q=1e7", "--tol", "5%", "--estimate", "off",
                 "--out", str(tmp_path / "other"), "--quiet"]) == 2
    assert "only where a built-in scene's measured front reaches the target" in capsys.readouterr().err


def test_tol_starts_from_the_front_of_the_cases_element_and_time_scheme(tmp_path):
    """The quadratic element's measured front is the smfem-quad9 series'; Gauss in time takes the
    points measured in Gauss time only (Newmark's at the same dt are 4 times less accurate)."""
    from smfem.studies.stored import read_front

    front = read_front("thick_cylinder")
    mine = front[(front.solver == "smfem-quad9") & (front.time_scheme == "gauss") & (front.total <= 0.01)]
    within = mine.sort_values("cpu_s").iloc[0]
    out = tmp_path / "tol"
    assert main(["run", "thick_cylinder", "--set", "element=quad9", "--set", "time_scheme=gauss", "--tol", "1%",
                 "--estimate", "off", "--out", str(out), "--quiet", "--no-fields"]) == 0
    run = json.loads((out / "summary.json").read_text())["tolerance"]["runs"][0]
    assert run["settings"]["dt"] == pytest.approx(within["dt"]) and run["settings"]["harmonics"] == within.harmonics
    assert run["measured_against_truth"] == pytest.approx(within.total) and within.total <= 0.01


def test_tol_claims_no_accuracy_for_a_run_outside_the_model(tmp_path, capsys):
    out = tmp_path / "tol"
    # strain 0.095 at 1.6 ms: past the 5 % limit in 40 % of the full window's CPU
    assert main(["run", "thick_cylinder", "--set", "plastic=true", "--set", "q=5e8", "--set", "t_end=1.6e-3",
                 "--tol", "50%", "--out", str(out), "--quiet", "--no-fields"]) == 0
    captured = capsys.readouterr()
    assert "outside the small-strain model: no accuracy" in captured.out.splitlines()[-1]
    assert "outside the small-strain model" in captured.err
    summary = json.loads((out / "summary.json").read_text())
    assert not summary["tolerance"]["runs"][-1]["valid"] and summary["error_estimate"]["claim"].startswith("none")


def test_fronts_are_kept_only_against_the_stored_truth_they_were_measured_with(tmp_path):
    from smfem.studies.stored import FRONT, read_front, write_fronts

    (tmp_path / "dome").mkdir()
    (tmp_path / "dome" / "summary.json").write_text(json.dumps({"key": "abc"}))
    fronts = pd.DataFrame({"case": ["dome", "dome", "rod_impact"], "solver": [SMFEM, REF2D, SMFEM],
                           "refine": [1, 1, 1], "dt": [1e-6] * 3, "cpu_s": [0.1, 0.2, 0.3],
                           "total": [0.05, 0.02, 0.1], "truth_key": ["abc", "abc", "abc"]})
    assert write_fronts(fronts, tmp_path) == ["dome"]  # no stored truth for the rod here
    assert len(read_front("dome", tmp_path)) == 2 and not (tmp_path / "rod_impact" / FRONT).exists()
    (tmp_path / "dome" / "summary.json").write_text(json.dumps({"key": "a new truth"}))
    assert read_front("dome", tmp_path) is None
    assert write_fronts(fronts, tmp_path) == []


def test_a_finer_mesh_takes_off_the_coarsening_first():
    from cases import rebuild
    from smfem.runs.tolerance import finer_mesh, growth

    case = get_case("notched_strip", {"coarsen": 4})
    assert finer_mesh(case, 2) == {"coarsen": 2} and finer_mesh(case, 4) == {"coarsen": 1}
    assert finer_mesh(rebuild(case, {"coarsen": 2}), 4) == {"coarsen": 1, "refine": 2}
    assert finer_mesh(get_case("dome"), 2) == {"refine": 2}
    assert growth(case, {"coarsen": 2, "dt": case.dt / 2}) == pytest.approx(8)
    three_d = get_case("rod_impact", {"dim": 3})
    assert growth(three_d, {"refine": 2}) == pytest.approx(8)


# --- the estimate serves the run: companions out of range or failing ----------------------------

def _planned(case, solver=SMFEM):
    p = E.plan(case, solver)
    return {c.name: (c.overrides, c.against) for c in p.companions}, p.upward, p.unmeasured


def test_companions_past_a_parameters_range_are_moved_to_the_finer_side_or_left_out():
    # twice the largest dt (1e3 s) is out of range: time from half the step instead
    comps, upward, unmeasured = _planned(get_case("thick_cylinder", {"dt": 1e3, "t_end": 3e3}))
    assert "time" not in comps and comps["time_up"] == ({"coarsen": 2, "dt": 500.0}, "space")
    assert upward == {"time": "time_up"} and not unmeasured
    # one step: twice the step does not fit the window
    assert _planned(get_case("thick_cylinder", {"t_end": 4e-5}))[0]["time_up"][0]["dt"] == 2e-5
    # one harmonic cannot be halved: two instead
    comps, upward, _ = _planned(get_case("thick_cylinder", {"harmonics": 1}))
    assert comps["harmonics_up"][0]["harmonics"] == 2 and upward["harmonics"] == "harmonics_up"
    # coarsen past its range: space left out, time and harmonics on the run's own mesh
    comps, _, unmeasured = _planned(get_case("thick_cylinder", {"coarsen": 16}))
    assert "space" not in comps and "coarsen 32" in unmeasured["space"]
    assert comps["time"] == ({"dt": 2 * get_case("thick_cylinder").dt}, "run") and comps["harmonics"][1] == "run"
    # segments of one element each: a mesh that cannot be halved
    assert "cannot be halved" in _planned(get_case("notched_cylinder", {"coarsen": 8}))[2]["space"]
    # every companion planned is a valid case
    for sets in ({"dt": 1e3, "t_end": 3e3}, {"coarsen": 16, "harmonics": 1}, {"t_end": 4e-5}):
        case = get_case("thick_cylinder", sets)
        for c in E.companions(case, SMFEM):
            get_case("thick_cylinder", {**sets, **c.overrides})


def _failing(run, fails):
    """``run`` but a companion whose case ``fails(case)`` names a failure: 'raise' raises,
    anything else returns a run that did not converge."""
    def wrapped(solver, case):
        how = fails(case)
        if how == "raise":
            raise RuntimeError("the companion broke\nacross two lines")
        result = run(solver, case)
        return SimpleNamespace(**{**vars(result), "converged": False, "message": how}) if how else result
    return wrapped


def test_a_failing_companion_leaves_its_part_out_and_the_others_measured():
    run, space, time, harmonics = _fake_solver()
    case = get_case("thick_cylinder", {"refine": 2, "dt": 1e-5, "t_end": 1e-3})
    result = run(SMFEM, case)
    # the coarse mesh raises: space unmeasured, time and harmonics measured on the run's own mesh
    est = E.estimate(case, SMFEM, result, run=_failing(run, lambda c: "raise" if c.refine == 1 else None))
    assert est["partial"] and set(est["unmeasured"]) == {"space"} and "the companion broke across" in est["failed"]["space"]
    assert est["companions"]["time"] == {"dt": 2e-5} and est["companions"]["harmonics"] == {"harmonics": 10}
    for parts in est["probes"].values():
        assert "space" not in parts and parts["time"] == pytest.approx(time(case), rel=0.1)
        assert parts["harmonics"] == pytest.approx(harmonics(case), rel=0.1)
    # the time companion does not converge: time unmeasured, the message kept
    est = E.estimate(case, SMFEM, result, run=_failing(run, lambda c: "step 3 diverged" if c.dt == 2e-5 else None))
    assert est["partial"] and set(est["unmeasured"]) == {"time"} and est["failed"] == {"time": "step 3 diverged"}
    assert all("time" not in p and "space" in p and "harmonics" in p for p in est["probes"].values())
    # only the third level fails: the part stands at its assumed order, the estimate whole
    est = E.estimate(case, SMFEM, result, run=_failing(run, lambda c: "no" if c.dt == 4e-5 else None))
    assert not est["partial"] and set(est["failed"]) == {"time2"}
    assert all(p["orders"]["time"] == E.ORDERS["time"] for p in est["probes"].values())
    # every companion fails: no part measured, no number claimed
    est = E.estimate(case, SMFEM, result, run=_failing(run, lambda c: "raise"))
    assert est["partial"] and "probes" not in est and set(est["unmeasured"]) == {"space", "time", "harmonics"}
    assert "none: no part measured" in E.summary_line(case, SMFEM, est)


def test_the_run_is_written_before_its_companions_and_kept_when_they_fail(tmp_path, capsys, monkeypatch):
    import smfem.api
    from smfem.runs.registry import solve

    out, calls = tmp_path / "run", []

    def solve_then_fail(solver, case, **kw):
        calls.append(case.params.get("coarsen", 1))
        if len(calls) > 1:  # a companion: the run is on disk already
            assert (out / "history.csv").exists() and (out / "summary.json").exists()
            raise RuntimeError("a companion broke")
        return solve(solver, case, **kw)

    monkeypatch.setattr(smfem.api, "solve_with", solve_then_fail)
    assert main(["run", "thick_cylinder", "--set", "t_end=2e-4", "--out", str(out), "--quiet", "--no-fields"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    est = summary["error_estimate"]
    assert summary["converged"] and est["partial"] and "probes" not in est and len(calls) > 2
    assert est["failed"]["space"] == "RuntimeError: a companion broke"
    printed = capsys.readouterr().out.splitlines()
    assert len(printed) == 2 and "error estimate none: no part measured (space: " in printed[1]
    assert len(pd.read_csv(out / "history.csv")) == get_case("thick_cylinder", {"t_end": 2e-4}).n_steps + 1


def test_tol_keeps_its_runs_when_a_later_run_fails(tmp_path, capsys, monkeypatch):
    """--tol's second run raises (out of memory at the finer settings): the first run, written
    as it finished, is the answer; exit 3 with one line saying why the search stopped."""
    from smfem.runs import tolerance
    from smfem.runs.registry import solve

    out, runs = tmp_path / "tol", []

    def second_run_fails(solver, case, **kw):
        if "fields" in kw:  # one of the search's runs (companions are called without)
            runs.append(case)
            if len(runs) == 2:
                raise MemoryError
        elif runs and len(runs) == 1:
            assert (out / "summary.json").exists()  # the first run is on disk before its companions
        return solve(solver, case, **kw)

    monkeypatch.setattr(tolerance, "solve", second_run_fails)
    args = ["run", "thick_cylinder", "--set", "t_end=1.6e-3", "--tol", "5%", "--out", str(out), "--quiet", "--no-fields"]
    assert main(args) == 3
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1 and "not met (the run at the next settings failed: MemoryError)" in err[0], err
    summary = json.loads((out / "summary.json").read_text())
    assert len(summary["tolerance"]["runs"]) == 1 and summary["params"]["refine"] == runs[0].refine


def test_a_partial_estimate_never_meets_the_tolerance():
    from smfem.runs.tolerance import Attempt

    case = get_case("thick_cylinder")
    whole = Attempt(case, None, {"method": "companions", "partial": False}, 0.001, 1.0, 1.0)
    partial = Attempt(case, None, {"method": "companions", "partial": True}, 0.001, 1.0, 1.0)
    assert whole.meets(0.01) and not partial.meets(0.01)
    assert Attempt(case, None, {"partial": True}, 0.5, 1.0, 1.0, measured=0.001).meets(0.01)  # the truth measured it


def test_a_mesh_section_that_cannot_be_coarsened_is_measured_upward_in_space():
    from smfem.runs.estimate import plan

    odd = plan(get_case("flywheel"), "smfem")
    assert odd.upward == {"space": "space_up"} and odd.companions[0].overrides == {"refine": 2}
    assert all(c.against in ("run", "time", "harmonics") for c in odd.companions)  # on the run's own mesh
    assert plan(get_case("flywheel", {"refine": 2}), "smfem").companions[0].overrides == {"refine": 1}
