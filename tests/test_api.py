"""The public Python interface (``import smfem``, :mod:`smfem.api`): what the command line does,
as functions; and the install's footprint (no generic top-level names)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
import tomllib
from pathlib import Path

import meshio
import numpy as np
import pandas as pd
import pytest

import smfem
from cases import ParameterError

ROOT = Path(__file__).resolve().parents[1]
#: a thick cylinder of five steps: a run of a fraction of a second
SHORT = {"t_end": 2e-4}


@pytest.fixture(scope="module")
def short_run():
    return smfem.run("thick_cylinder", **SHORT)


def test_import_smfem_shows_the_interface_and_loads_no_framework_until_asked():
    names = set(dir(smfem))
    assert {"load", "run", "read", "compare", "truth", "error", "study", "report", "scenes", "solvers",
            "Result", "__version__"} <= names
    code = "import sys, smfem.model; print(sorted(m for m in ('smfem.api', 'reports', 'reference_fem') if m in sys.modules))"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip() == "[]"
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        smfem.nothing  # noqa: B018


def test_the_interfaces_docstring_example_runs():
    import doctest

    import smfem.api

    result = doctest.testmod(smfem.api)
    assert result.attempted >= 6 and result.failed == 0


def test_load_takes_a_name_a_scene_file_or_a_case_with_parameters():
    by_name = smfem.load("thick_cylinder", dt=1e-5)
    by_file = smfem.load(ROOT / "examples" / "thick_cylinder.toml", dt=1e-5)
    assert by_name.dt == by_file.dt == 1e-5 and by_name.probe_names == by_file.probe_names
    assert smfem.load(by_name) is by_name and smfem.load(by_name, refine=2).refine == 2
    assert "dome" in smfem.scenes() and {"smfem", "reference-2d"} <= set(smfem.solvers())
    with pytest.raises(ParameterError, match="nu=0.7 is out of range"):
        smfem.load("dome", nu=0.7)
    with pytest.raises(ParameterError, match="unknown key 'poisson'"):
        smfem.load("dome", poisson=0.3)
    with pytest.raises(ParameterError, match="unknown case"):
        smfem.load("no_such_scene")


def test_a_run_gives_histories_a_summary_fields_and_its_error_estimate(short_run):
    r = short_run
    case = smfem.load("thick_cylinder", **SHORT)
    assert isinstance(r.history, pd.DataFrame) and list(r.history.columns) == ["t", *case.probe_names]
    assert len(r.history) == case.n_steps + 1 and r.history.t.iloc[-1] == pytest.approx(case.t_end)
    s = r.summary
    assert s["case"] == "thick_cylinder" and s["solver"] == "smfem" and s["n_steps"] == case.n_steps
    assert s["validity"]["valid"] and json.dumps(s, default=str)
    assert isinstance(r.mesh, meshio.Mesh) and r.mesh.points.shape[1] == 3
    assert r.error_estimate and math.isfinite(r.estimate) and r.estimate > 0
    grid = r.to_pyvista()
    assert grid.n_points == len(r.mesh.points)


def test_a_solver_option_goes_in_as_a_keyword_and_a_bad_one_is_a_parameter_error():
    r = smfem.run("thick_cylinder", estimate=False, fields=False, bbar=True, **SHORT)
    assert r.summary["options"] == {"bbar": True} and r.mesh is None and r.error_estimate is None
    with pytest.raises(ValueError, match="without fields"):
        r.to_pyvista()
    with pytest.raises(ParameterError):
        smfem.run("thick_cylinder", estimate=False, refine=0)


def test_written_and_read_back_the_run_is_the_same(short_run, tmp_path):
    out = short_run.write(tmp_path / "run")
    assert {"history.csv", "summary.json", "fields.vtu"} <= {p.name for p in out.iterdir()}
    back = smfem.read(out)
    pd.testing.assert_frame_equal(back.history, short_run.history, rtol=1e-9)
    assert back.case.params == short_run.case.params and back.estimate == pytest.approx(short_run.estimate)
    # a scene from a file: read with its file
    pipe = smfem.run(ROOT / "examples" / "pipe.toml", estimate=False, fields=False, t_end=1e-4)
    again = smfem.read(pipe.write(tmp_path / "pipe"), scene=ROOT / "examples" / "pipe.toml")
    assert again.case.params == pipe.case.params and again.summary["n_dof"] == pipe.summary["n_dof"]
    with pytest.raises(ParameterError, match="unknown case 'pipe'"):
        smfem.read(tmp_path / "pipe")


def test_compare_two_solvers_and_the_error_against_the_stored_truth():
    case = smfem.load("thick_cylinder")
    mine = smfem.run(case, estimate=False, fields=False)
    ref = smfem.run(case, solver="reference-2d", estimate=False, fields=False)
    table = smfem.compare(mine, ref)
    assert list(table.probe) == case.probe_names and (table.measure == "max-norm").all()
    assert (table.difference > 0).all() and (table.difference < 0.1).all()
    truth = smfem.truth("thick_cylinder")
    assert truth is not None and truth.source != "computed"
    total = smfem.error(mine)
    assert total == smfem.error(mine, truth) and 0 < total < 0.5
    # the error is the worst displacement probe's, measured as compare measures it
    against_truth = [smfem.compare(mine, _as_result(truth, case)).set_index("probe").difference[p.name]
                     for p in case.probes if p.field in ("u", "v") and truth.converged(p.name)]
    assert total == pytest.approx(max(against_truth), rel=1e-12)
    assert smfem.truth(smfem.load("thick_cylinder", t_end=2e-3)) is None  # other physics: no truth
    with pytest.raises(ValueError, match="no stored truth"):
        smfem.error(smfem.run("thick_cylinder", estimate=False, fields=False, t_end=2e-3))


def _as_result(truth, case):
    from cases.result import RunResult

    return smfem.Result(case, "truth", RunResult(truth.t, truth.values, n_dof=0, iterations=[]))


def test_the_install_takes_no_generic_top_level_name():
    """pyproject's package list: only the layout's own packages at the top (``smfem``,
    ``reference_fem``, ``cases``, ``reports``); the command line, the runs, the studies and the
    stored truths live under ``smfem``."""
    from setuptools import find_packages

    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    found = find_packages(str(ROOT), include=config["tool"]["setuptools"]["packages"]["find"]["include"])
    assert {p.split(".")[0] for p in found} == {"smfem", "reference_fem", "cases", "reports"}
    assert {"smfem.cli", "smfem.runs", "smfem.studies", "smfem.truths"} <= set(found)
    assert config["project"]["scripts"] == {"smfem": "smfem.cli:main"}
    assert "smfem.truths" in config["tool"]["setuptools"]["package-data"]


def test_python_dash_m_smfem_is_the_command_line():
    done = subprocess.run([sys.executable, "-m", "smfem", "cases"], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0 and "thick_cylinder" in done.stdout
