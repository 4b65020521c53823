"""Bad input (docs/contract.md): exit status 2, one clear line, no traceback, nothing written; and
any valid set of parameters gives finite histories or a clear error.

The mistakes are generated from each case's parameter specs, so a new key is covered as soon
as it is declared. The property tests run tiny windows (at most 4 steps, few harmonics, refine
at most 2; the reference solver in 2D) so that a hundred examples take well under a minute; the
default run tries 20 of SMFEM's, and their slow twins (``-m slow``) 60 and 400.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, event, given, settings, strategies as st
from hypothesis.control import currently_in_test_context

from cases import CASES, ParameterError, get_case, parse_sets
from cases.params import MAX_STEPS
from cases.params import out_of_range
import smfem.api
from smfem.cli import main
from reports.stability_study import bad_input
from smfem.runs.registry import lookup, solvers


def cli_outcome(args: list[str]) -> dict:
    """Run the command line with ``--out`` in a scratch directory: exit status, stderr, whether
    anything was written, and the history table if one was."""
    import contextlib
    import io
    import tempfile

    import pandas as pd

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            code = main(args + ["--out", str(out)])
        history = pd.read_csv(out / "history.csv") if (out / "history.csv").exists() else None
        return {"code": code, "stderr": err.getvalue().strip(), "written": out.exists(), "history": history}


def run_cli(args, capsys) -> tuple[int, str]:
    code = main(args)
    captured = capsys.readouterr()
    return code, captured.err.strip()


def assert_one_clear_line(err: str, needle: str):
    assert "Traceback" not in err
    assert len(err.splitlines()) == 1, err
    assert err.startswith("smfem: error: ") and needle in err, err


@pytest.fixture
def one_parser(monkeypatch):
    """For a test that sweeps ``main`` over a hundred bad values: the command line's parser built
    once, not on every call (``main`` builds the same one anew each time, and pins the BLAS
    threads this test process has pinned already: 30 ms a call, most of a sweep). What is
    checked is what ``main`` does with the arguments: the parsing, the checks, the refusal."""
    import smfem.cli

    parser = smfem.cli.build_parser()
    monkeypatch.setattr(smfem.cli, "build_parser", lambda: parser)
    monkeypatch.setattr(smfem.cli.threads, "pin", lambda: 1)


@pytest.mark.parametrize("name", CASES)
@pytest.mark.parametrize("solver", ["smfem", "reference"])
def test_every_key_out_of_range_exits_2_naming_the_key(name, solver, one_parser):
    """Every key of every case, every kind of bad value (past each bound, the open bounds, nan,
    inf, -inf, wrong types): exit 2, one line naming the key and its allowed range, nothing
    written."""
    count = 0
    for key, spec in CASES[name].SPECS.items():
        for text in out_of_range(spec):
            o = cli_outcome(["run", name, "--solver", solver, "--set", f"{key}={text}"])
            assert o["code"] == 2, (key, text, o)
            assert_one_clear_line(o["stderr"], key)
            assert "out of range" not in o["stderr"] or spec.describe() in o["stderr"], o
            assert not o["written"], (key, text)
            count += 1
    assert count > 5 * len(CASES[name].SPECS)


@pytest.mark.parametrize("solver", [s.name for s in solvers() if s.command_line and s.options()])
def test_every_solver_option_out_of_range_exits_2_naming_it(solver, one_parser):
    """A solver's own options (``--set anderson=-3``, ``relaxation=5``, ``grading=0``) are
    checked as case parameters are: exit 2, one line naming the option and its range, nothing
    written."""
    count = 0
    for key, spec in lookup(solver).options().items():
        for text in out_of_range(spec):
            o = cli_outcome(["run", "dome", "--solver", solver, "--set", f"{key}={text}"])
            assert o["code"] == 2, (key, text, o)
            assert_one_clear_line(o["stderr"], key)
            assert spec.describe() in o["stderr"] and not o["written"], (key, text, o)
            count += 1
    # every option swept: at least 3 bad values each (a flag or a word has 3, a number 5 or more)
    assert count >= 3 * len(lookup(solver).options())


@pytest.mark.parametrize("text", ["-5", "0", "nan", "inf", "1e300"])
def test_max_cpu_out_of_range_exits_2(text):
    o = cli_outcome(["run", "thick_cylinder", "--tol", "5%", "--max-cpu", text])
    assert o["code"] == 2 and not o["written"]
    assert_one_clear_line(o["stderr"], "--max-cpu")


def test_the_reports_bad_input_sweep_refuses_every_value():
    rows = bad_input()
    assert len(rows) > 100
    assert all(r["refused"] and r["lines"] == 1 and r["names_key"] and r["names_range"] for r in rows), \
        [r for r in rows if not (r["refused"] and r["names_key"] and r["names_range"])][:3]


@pytest.mark.parametrize(
    "args,needle",
    [
        (["run", "no_such_case"], "unknown case"),
        (["run", "dome", "--set", "bogus=1"], "unknown key 'bogus'"),
        (["run", "dome", "--set", "contrast=0.5"], "unknown key 'contrast'"),  # another case's key
        (["run", "dome", "--set", "dt"], "malformed --set"),
        (["run", "dome", "--set", "=1"], "malformed --set"),
        (["run", "dome", "--set", "dt="], "malformed --set"),
        (["run", "dome", "--set", "dt==1"], "is not a value"),
        (["run", "dome", "--set", "dt=1e-5)"], "is not a value"),
        (["run", "dome", "--set", "dt=" + "(" * 200], "is not a value"),
        (["run", "dome", "--set", "dt=" + "9" * 400], "dt"),  # an integer beyond the float range
        (["run", "dome", "--set", "dt=1e-5", "--set", "t_end=1e-6"], "must not exceed t_end"),
        (["run", "dome", "--set", "dt=1e-9", "--set", "t_end=1"], f"at most {MAX_STEPS} time steps"),
        (["run", "notched_strip", "--set", "notch_depth=0.05"], "notch_depth"),  # the probe would be in the void
        (["run", "dome", "--set", "q=0"], "nothing moves"),  # a valid value, a clear refusal by the solver
        (["run", "dome", "--solver", "ansys"], "invalid choice"),
        # CalculiX's procedures: refused before ccx runs (so also where it is not installed)
        (["run", "dome", "--solver", "calculix", "--set", "procedure=newmark"], "procedure"),
        (["run", "notched_strip", "--solver", "calculix", "--set", "procedure=modal"], "takes no plasticity"),
        (["run", "rod_impact", "--solver", "calculix", "--set", "procedure=modal"], "takes no contact"),
        (["run", "rod_impact", "--solver", "calculix", "--set", "procedure=explicit"], "contact is not exported"),
        (["run", "dome", "--solver", "calculix", "--set", "procedure=explicit"], "axisymmetric"),
        (["run", "dome", "--solver", "calculix", "--set", "modes=20"], "the modal procedure's option"),
        (["run", "dome", "--solver", "calculix", "--set", "procedure=modal", "--set", "modes=0"], "modes"),
        (["run", "dome", "--solver", "calculix", "--set", "procedure=modal", "--set", "modes=5000"], "free dofs"),
        (["run", "dome", "--solver", "smfem", "--set", "procedure=modal"], "an option of calculix"),
        (["run"], "required: case"),
        (["run", "dome", "--tol", "5%", "--max-cpu", "-5"], "--max-cpu"),
        (["study", "dome", "--workers", "0"], "--workers"),
        (["report", "--workers", "100000"], "--workers"),
    ],
)
def test_user_mistakes_exit_2_with_one_line(tmp_path, capsys, args, needle):
    out = tmp_path / "out"
    code, err = run_cli(args + ["--out", str(out)], capsys)
    assert code == 2
    assert_one_clear_line(err, needle)
    assert not out.exists()


@pytest.mark.parametrize("command", ["run", "study", "truth"])
def test_a_scene_file_nested_5000_deep_exits_2_with_one_line(tmp_path, capsys, command):
    """A value 5000 arrays deep (past the TOML reader's recursion) is one line, as every other
    reading failure of a scene file."""
    scene = tmp_path / "deep.toml"
    scene.write_text('name = "deep"\na = ' + "[" * 5000 + "]" * 5000 + "\n")
    out = tmp_path / "out"
    code, err = run_cli([command, str(scene), "--out", str(out)], capsys)
    assert code == 2
    assert_one_clear_line(err, "nested too deeply")
    assert not out.exists()
    assert "..." in run_cli(["run", "dome", "--set", "dt=" + "[" * 5000], capsys)[1]  # the value cut, not echoed


@pytest.mark.parametrize("where", ["under a file", "is a file", "in /proc"])
@pytest.mark.parametrize("solver", ["smfem", "reference"])
def test_unwritable_out_exits_2_before_any_work(tmp_path, capsys, monkeypatch, where, solver):
    blocker = tmp_path / "file"
    blocker.write_text("")
    out = {"under a file": blocker / "sub" / "deeper", "is a file": blocker, "in /proc": Path("/proc/smfem-out")}[where]
    monkeypatch.setattr(smfem.api, "solve_with", lambda *a, **k: pytest.fail("the solver ran"))
    code, err = run_cli(["run", "dome", "--solver", solver, "--out", str(out)], capsys)
    assert code == 2
    assert_one_clear_line(err, "--out")
    assert blocker.read_text() == "" and sorted(tmp_path.iterdir()) == [blocker]


def test_out_of_memory_is_one_line_not_a_traceback(tmp_path, capsys, monkeypatch):
    def exhausted(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr(smfem.api, "solve_with", exhausted)
    code, err = run_cli(["run", "dome", "--out", str(tmp_path / "out")], capsys)
    assert code == 2
    assert_one_clear_line(err, "out of memory")
    assert not (tmp_path / "out").exists()


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.one_of(
    st.text(max_size=40),
    st.builds("{}={}".format, st.sampled_from([*CASES["dome"].SPECS, "bogus", ""]),
              st.one_of(st.text(max_size=20), st.floats().map(repr), st.integers().map(str))),
))
def test_any_set_text_parses_or_raises_parameter_error(text):
    """Whatever follows ``--set``: a valid case, or ParameterError with one line; nothing else
    escapes."""
    try:
        get_case("dome", parse_sets([text]))
    except ParameterError as exc:
        assert len(str(exc).splitlines()) == 1, str(exc)


# --- valid parameters: finite histories or a clear error ---------------------------------------------

#: keep the property runs tiny
MAX_HARMONICS, MAX_REFINE, MAX_STEPS_RUN = 6, 2, 4


def valid_value(key, spec):
    """A strategy over the values ``spec`` accepts: log-uniform over positive ranges (so every
    decade is tried), with the bounds themselves."""
    if spec.type is bool:
        return st.booleans()
    if spec.choices is not None:
        return st.sampled_from(spec.choices)
    if spec.type is int:
        cap = {"harmonics": MAX_HARMONICS, "refine": MAX_REFINE}.get(key, spec.hi)
        return st.integers(spec.lo, min(spec.hi, cap))
    lo, hi = spec.lo, spec.hi
    if lo > 0:
        first = math.nextafter(lo, math.inf) if spec.open_lo else lo
        last = math.nextafter(hi, 0.0) if spec.open_hi else hi
        inside = st.floats(math.log10(lo), math.log10(hi)).map(lambda e: min(max(10.0**e, first), last))
        edges = [b for b, is_open in ((lo, spec.open_lo), (hi, spec.open_hi)) if not is_open]
        return st.one_of(st.sampled_from(edges), inside) if edges else inside
    return st.floats(lo, hi, exclude_min=spec.open_lo, exclude_max=spec.open_hi)


@st.composite
def valid_run(draw, solver="smfem", max_refine=MAX_REFINE):
    """``(case name, solver, --set values)`` of a tiny run with valid parameters."""
    name = draw(st.sampled_from(sorted(CASES)))
    specs = CASES[name].SPECS
    sets = {key: draw(valid_value(key, spec)) for key, spec in specs.items()
            if key not in ("dt", "t_end", "dim", "refine") and draw(st.booleans())}
    # a mesh section's refine splits each element k x k, and its 9-node model with the error
    # estimate's finer companion is 9 s a run (the flywheel's): the 4-node one at refine 1 takes
    # the same paths of parameter handling (tests/test_mesh_sections*.py run the 9-node one)
    mesh = get_case(name).section.kind == "mesh"
    if mesh:
        sets.pop("element", None)
    sets["refine"] = draw(st.integers(1, 1 if mesh else max_refine))
    sets.setdefault("harmonics", draw(st.integers(1, MAX_HARMONICS)))  # the strip's default is 80
    sets["dim"] = 2  # the 3-D reference is minutes at the extremes; test_cli covers it
    dt = draw(valid_value("dt", specs["dt"])) if draw(st.booleans()) else CASES[name].DEFAULTS["dt"]
    sets["dt"], sets["t_end"] = dt, dt * draw(st.integers(1, MAX_STEPS_RUN))
    return name, solver, sets


def note(text):
    if currently_in_test_context():
        event(text)


def run_args(name, solver, sets) -> list[str]:
    return ["run", name, "--solver", solver, "--quiet", "--no-fields",
            *(arg for k, v in sets.items() for arg in ("--set", f"{k}={v!r}"))]


def check_run(name, solver, sets):
    """Run through the command line; return the exit status after checking the contract."""
    o = cli_outcome(run_args(name, solver, sets))  # an exception here is the traceback the contract forbids
    code, err = o["code"], o["stderr"]
    note(f"{name} {solver}: exit {code}")
    assert code in (0, 2, 3), (code, err)
    if code == 2:
        assert_one_clear_line(err, "")
        assert not o["written"]
        return code
    assert np.isfinite(o["history"].to_numpy()).all(), (code, err)
    if code == 3:  # the message names the case (a variant's own name) and the step; the history up to it is written
        assert err.startswith(f"smfem: {get_case(name, sets).name}: ") and "step" in err, err
    else:
        assert len(o["history"]) == get_case(name, sets).n_steps + 1
    return code


@settings(max_examples=20, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(valid_run())
def test_valid_parameters_give_finite_histories_or_a_clear_error(run):
    """20 tiny runs with valid parameters; the slow twins below run 60 of them and 400 random
    ones."""
    check_run(*run)


@pytest.mark.slow
@settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(valid_run())
def test_valid_parameters_give_finite_histories_or_a_clear_error_60_examples(run):
    check_run(*run)


@settings(max_examples=15, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(valid_run("reference", max_refine=1))
def test_valid_parameters_reference_solver(run):
    check_run(*run)


@pytest.mark.parametrize("solver", ["smfem", "reference"])
def test_quasi_static_collapse_is_a_clear_error(solver, tmp_path):
    """Ideal plasticity far beyond the collapse load with a step so long that inertia vanishes
    (tau_s = 100 Pa under 0.85e8 Pa, dt = 1000 s): found by the property test below. Whether
    the run or its companions converge differs between machines; what holds on every one: the
    run's history is written, and where it finished, its estimate is written too, no
    companion's settings leave a parameter's range (twice the largest dt made one, which threw
    the finished run away), and a part it could not measure is named."""
    out = tmp_path / "run"
    sets = {"harmonics": 4, "tau_s": 100.0, "dt": 1000.0, "t_end": 3000.0}
    code = main(run_args("notched_strip", solver, sets) + ["--out", str(out)])
    history = pd.read_csv(out / "history.csv")
    assert code in (0, 3) and len(history) >= 1 and np.isfinite(history.to_numpy()).all()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] == (code == 0)
    if code == 0:
        est = summary["error_estimate"]
        case = get_case("notched_strip", sets)
        for overrides in est["companions"].values():
            get_case("notched_strip", {**sets, **overrides})  # within every range
        # twice the step (2000 s) is past dt's range: time is measured at half the step, if at all
        assert "time" not in est["companions"]
        assert est["companions"].get("time_up", {}).get("dt") == 500.0 or "time" in est["unmeasured"], est
        assert est["partial"] == bool(est.get("unmeasured")) and set(est.get("unmeasured", {})) <= {"space", "time",
                                                                                                   "harmonics"}
        assert est["partial"] or {"space", "time", "harmonics"} <= set(est["probes"]["mid_uz"]), est
        assert case.n_steps + 1 == len(history)


def test_a_singular_contact_layer_in_an_estimates_companion_is_a_clear_error():
    """Found by the property test: the rod at E = 1e15 Pa, rho = 1, dt = t_end = 1 s. The run
    finishes; the coarse companion's contact face system is singular, which raised numpy's
    LinAlgError through 'smfem run'; now the step fails with a message and the estimate says
    which companion did not finish."""
    o = cli_outcome(run_args("rod_impact", "smfem", {"E": 1e15, "rho": 1.0, "gap": 0.017578125, "refine": 1,
                                                     "harmonics": 1, "dim": 2, "dt": 1.0, "t_end": 1.0}))
    assert o["code"] in (0, 3) and np.isfinite(o["history"].to_numpy()).all()


@pytest.mark.slow
def test_diverged_plastic_newton_is_reported_not_written_as_nan():
    """Found by the property test: E = 1e15 Pa, tau_s = 1 Pa, rho = 8e-7. The reference's
    Newton ran to 5e147 and NaN stresses and passed for converged (NaN compares false); now it
    stops the run (exit 3, the step named). About 50 s: the diverging iterates are slow."""
    sets = {"harmonics": 5, "E": 1e15, "rho": 8.38503011040698e-07, "tau_s": 1.0, "notch_depth": 1.0177836226162974e-4,
            "contrast": 0.2252876949381178, "refine": 1, "dim": 2, "dt": 3.2e-06, "t_end": 3.2e-06}
    o = cli_outcome(run_args("notched_strip", "reference", sets))
    assert o["code"] == 3 and np.isfinite(o["history"].to_numpy()).all()
    assert o["stderr"].startswith("smfem: notched_strip: step 1 ") and "diverged" in o["stderr"]


@pytest.mark.slow
@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(valid_run())
def test_valid_parameters_many_random_examples(run):
    check_run(*run)


@pytest.mark.slow
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(valid_run("reference"))
def test_valid_parameters_many_random_examples_reference_solver(run):
    check_run(*run)
