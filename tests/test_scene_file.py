"""Scenes from a TOML file (docs/scenes.md, "Scenes from a file"): the five example files are the
built-in scenes, field by field and history by history; every mistake in a file is one line
naming the file and the key, exit status 2, nothing written; a scene of one's own runs."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from cases import CASES, VARIANTS, ParameterError, get_case, rebuild
from cases.params import COMMON
from cases.scene_file import OPTIONAL, REQUIRED, from_text
from smfem.cli import main
from smfem.runs.registry import solve

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
#: every field of a Case that a solver reads
SOLUTION_FIELDS = ("name", "body", "section", "material", "loads", "supports", "probes", "params", "length",
                   "cutouts", "contrast", "initial_velocity", "wall", "symmetric", "axisymmetric", "regions", "contacts")

#: a scene of one's own: a short elastic prism with a pressure patch on its top face
USER_SCENE = """\
name = "short_prism"
title = "Short elastic prism, pressure on a patch of the top face"
body = "prism"
length = 0.5

[params]
dt = 1e-6
t_end = 5e-6
harmonics = 8
E = 2.1e11
nu = 0.3
rho = 7.8e3
tau_s = 1.7e8
q = 1e6

[section]
kind = "rect"
s = { breaks = [0.0, 0.01], counts = [1], refinable = false }
t = { breaks = [0.0, 0.05], counts = [4] }
edges = { top = "t_max" }

[[load]]
q = "q"
edge = "top"
x3_intervals = [[0.2, 0.3]]

[[support]]
edge = "all"
components = [1]

[[probe]]
name = "mid_uz"
kind = "point"
field = "u"
component = [2]
point = [0.0, 0.05, 0.25]
"""


def example(name: str) -> Path:
    return EXAMPLES / f"{name}.toml"


def tiny(name: str) -> dict:
    """Three time steps of the case."""
    return {"t_end": 3 * get_case(name).dt}


@pytest.mark.parametrize("name", [*CASES, *VARIANTS])
def test_example_file_is_the_builtin_scene(name):
    builtin, from_file = get_case(name), get_case(example(name))
    fixed = VARIANTS[name][1] if name in VARIANTS else {}  # a variant's own keys: the file writes their effect
    assert {**from_file.params, **fixed} == builtin.params
    for field in SOLUTION_FIELDS:
        assert field == "params" or getattr(from_file, field) == getattr(builtin, field), field
    for key in ("plastic_zone_times", "comparison_window_s", "singular_probes"):
        assert from_file.references.get(key) == builtin.references.get(key), key


@pytest.mark.parametrize("name", [*CASES, *VARIANTS])
def test_example_file_gives_the_builtin_histories(name):
    a, b = (solve("smfem", get_case(c, tiny(name))) for c in (name, example(name)))
    assert list(b.history) == list(a.history) and np.array_equal(b.t, a.t)
    assert all(np.array_equal(b.history[k], a.history[k]) for k in a.history)


def test_example_file_gives_the_builtin_histories_with_the_reference():
    a, b = (solve("reference", get_case(c, tiny("thick_cylinder"))) for c in ("thick_cylinder", example("thick_cylinder")))
    assert all(np.array_equal(b.history[k], a.history[k]) for k in a.history)


def test_set_and_rebuild_work_on_a_file_scene():
    case = get_case(example("notched_strip"), {"E": 2e11, "notch_depth": 0.0})
    builtin = get_case("notched_strip", {"E": 2e11, "notch_depth": 0.0})
    assert case.material.E == 2e11 and case.cutouts == ()
    assert all(getattr(case, f) == getattr(builtin, f) for f in SOLUTION_FIELDS)
    again = rebuild(case, {"dim": 3})
    assert again.params == {**case.params, "dim": 3} and again.source == case.source
    assert rebuild(get_case("dome"), {"dim": 3}) == get_case("dome", {"dim": 3})
    with pytest.raises(ParameterError, match="unknown key 'v0'"):
        get_case(example("notched_strip"), {"v0": 1.0})


def test_params_defaults_cover_the_common_keys():
    # coarsen (an error estimate's companion), element and time_scheme (SMFEM's section element
    # and time integration), theta_elements and mirror (the 3D reference's ring) are
    # overrides only: without a default, a case's params hold them only when set, and the
    # stored truths' keys stay as they were
    overrides_only = {"coarsen", "element", "time_scheme", "theta_elements", "mirror"}
    assert set(REQUIRED) | set(OPTIONAL) == set(COMMON) - overrides_only and not set(REQUIRED) & set(OPTIONAL)


@pytest.mark.parametrize("solver", ["smfem", "reference"])
def test_run_of_a_file_writes_into_out_scene_solver(tmp_path, monkeypatch, solver):
    monkeypatch.chdir(tmp_path)
    args = ["run", str(example("thick_cylinder")), "--solver", solver, "--set", "dt=1e-4", "--set", "t_end=3e-4"]
    assert main(args + ["--quiet", "--no-fields"]) == 0
    summary = json.loads((tmp_path / "out" / f"thick_cylinder-{solver}" / "summary.json").read_text())
    assert summary["case"] == "thick_cylinder" and summary["params"]["dt"] == 1e-4 and summary["n_steps"] == 3


def test_a_scene_of_ones_own_runs(tmp_path):
    scene, out = tmp_path / "short_prism.toml", tmp_path / "out"
    scene.write_text(USER_SCENE)
    assert main(["run", str(scene), "--out", str(out), "--quiet", "--no-fields"]) == 0
    history = pd.read_csv(out / "history.csv")
    assert list(history.columns) == ["t", "mid_uz"] and len(history) == 6
    assert history["mid_uz"].iloc[-1] < 0  # pressed down


def test_the_scene_of_the_docs_builds():
    text = (EXAMPLES.parent / "docs" / "scenes.md").read_text()
    block = text.split("```toml\n", 1)[1].split("```", 1)[0]
    case = from_text(block, "scenes.md")
    assert case.name == "short_prism" and case.probe_names == ["mid_uz"] and case.loads[0].q == 1e6


@pytest.mark.parametrize(
    "old,new,needle",
    [
        ('kind = "rect"', 'kind = "rect', "not valid TOML"),  # syntax error
        ('edge = "top"', 'edeg = "top"', "load[1].edeg: unknown key"),
        ('[[support]]', '[materials]\nE_T = 1e9\n\n[[support]]', "materials: unknown key"),
        ('dt = 1e-6\n', '', "params.dt: missing"),
        ('counts = [4]', 'counts = ["4"]', "section.t.counts"),
        ('nu = 0.3', 'nu = 0.7', "params.nu: nu=0.7 is out of range"),
        ('edge = "top"', 'edge = "lid"', "load[1].edge: 'lid'"),
        ('kind = "point"', 'kind = "probe"', "probe[1].kind: 'probe'"),
        ('[[0.2, 0.3]]', '[[0.2, 0.7]]', "load[1].x3_intervals"),  # beyond the prism's length
        ('q = "q"', 'q = 1e6', "params.q"),  # a parameter nothing reads
        ('q = "q"', 'q = "Q"', "load[1].q: 'Q' names no parameter"),
        ('point = [0.0, 0.05, 0.25]', 'point = [0.0, 0.06, 0.25]', "probe[1].point"),
        ('length = 0.5', 'length = "long"', "length"),
        ('body = "prism"', 'body = "prism"\nsymmetric = true', "symmetric"),
    ],
)
def test_mistakes_in_a_file_exit_2_naming_file_and_key(tmp_path, capsys, old, new, needle):
    assert USER_SCENE.count(old) == 1
    scene, out = tmp_path / "scene.toml", tmp_path / "out"
    scene.write_text(USER_SCENE.replace(old, new))
    assert main(["run", str(scene), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith(f"smfem: error: {scene}: ") and needle in err, err
    assert not out.exists()


@pytest.mark.parametrize(
    "args,needle",
    [
        (["--set", "notch_depth=0.01"], "unknown key 'notch_depth' for case 'short_prism'"),
        (["--set", "dt=0"], "dt=0 is out of range"),
    ],
)
def test_mistakes_in_set_on_a_file_exit_2(tmp_path, capsys, args, needle):
    scene, out = tmp_path / "scene.toml", tmp_path / "out"
    scene.write_text(USER_SCENE)
    assert main(["run", str(scene), "--out", str(out)] + args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("smfem: error: ") and needle in err, err
    assert not out.exists()


def test_a_missing_file_exits_2_naming_it(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(tmp_path / "missing.toml"), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith(f"smfem: error: {tmp_path / 'missing.toml'}: cannot read")
    assert not out.exists()
