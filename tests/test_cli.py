"""The command line of docs/contract.md."""

import json
import subprocess
import sys

import meshio
import numpy as np
import pandas as pd
import pytest

from cases import get_case
from smfem.cli import main


def test_run_thick_cylinder_writes_the_contract_files(tmp_path):
    out = tmp_path / "run"
    assert main(["run", "thick_cylinder", "--set", "dt=1e-5", "--out", str(out), "--quiet"]) == 0
    history = pd.read_csv(out / "history.csv")
    assert list(history.columns) == ["t", "A_ur", "B_ut", "C_ur"]
    assert len(history) == 401 and history["t"].iloc[0] == 0 and history["t"].iloc[-1] == pytest.approx(4e-3)
    summary = json.loads((out / "summary.json").read_text())
    for key in ("case", "solver", "params", "n_dof", "n_steps", "wall_time_s", "cpu_time_s", "iterations",
                "converged", "harmonics_used", "version"):
        assert key in summary
    assert summary["params"]["dt"] == 1e-5 and summary["n_steps"] == 400 and summary["converged"] is True
    assert summary["iterations"] == {"mean": 1.0, "max": 1, "per_step": [1] * 400}
    assert summary["harmonics_used"] == ["0c", "2c", "6c", "10c", "14c", "18c"]
    mesh = meshio.read(out / "fields.vtu")
    assert mesh.point_data["displacement"].shape == (len(mesh.points), 3)
    assert mesh.cells[0].type == "hexahedron"


def test_fields_carry_the_synthesized_probe_value(tmp_path):
    """The 3-D field at point A (r2, theta = 0) equals the last A_ur of the history."""
    main(["run", "thick_cylinder", "--out", str(tmp_path), "--quiet"])
    mesh = meshio.read(tmp_path / "fields.vtu")
    history = pd.read_csv(tmp_path / "history.csv")
    import numpy as np

    a = np.argmin(np.linalg.norm(mesh.points - [2.0, 0.0, 0.0], axis=1))
    assert mesh.point_data["displacement"][a, 0] == pytest.approx(history["A_ur"].iloc[-1], rel=1e-9)


@pytest.mark.parametrize(
    "args,needle",
    [
        (["run", "no_such_case"], "unknown case"),
        (["run", "dome", "--set", "nu=0.5"], "nu"),
        (["run", "dome", "--set", "dt=inf"], "dt"),
        (["run", "dome", "--set", "harmonics=0"], "harmonics"),
        (["run", "dome", "--set", "bogus=1"], "bogus"),
        (["run", "dome", "--set", "dt"], "KEY=VALUE"),
        (["run", "dome", "--solver", "ansys"], "solver"),
        (["frobnicate"], "invalid choice"),
        (["run", "thick_cylinder", "--set", "time_scheme=gauss", "--set", "plastic=true"], "time_scheme=gauss"),
        (["run", "dome", "--solver", "reference", "--set", "time_scheme=gauss"], "time_scheme=gauss"),
    ],
)
def test_user_mistakes_exit_2_with_one_line_and_write_nothing(tmp_path, capsys, args, needle):
    out = tmp_path / "out"
    assert main(args + ["--out", str(out)] if args[0] == "run" else args) == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and len(err.splitlines()) == 1 and "Traceback" not in err
    assert not out.exists()


def test_unwritable_out_exits_2(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["run", "dome", "--out", str(blocker / "sub")]) == 2
    assert "--out" in capsys.readouterr().err


def test_cases_lists_every_case_and_key(capsys):
    assert main(["cases"]) == 0
    text = capsys.readouterr().out
    for name in ("dome", "thick_cylinder", "notched_cylinder", "notched_strip", "rod_impact"):
        assert name in text
    assert "notch_depth" in text and "friction" in text


def test_console_script_and_module_entry_point(tmp_path):
    done = subprocess.run([sys.executable, "-m", "smfem", "run", "dome", "--set", "t_end=1e-4",
                           "--out", str(tmp_path), "--quiet"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert len(pd.read_csv(tmp_path / "history.csv")) == get_case("dome", {"t_end": 1e-4}).n_steps + 1


@pytest.mark.parametrize("solver", ["smfem", "reference"])
def test_every_n_steps_writes_a_paraview_time_series(solver, tmp_path):
    """``--every 5`` on 10 steps: fields.pvd lists t = 0, 5 dt and 10 dt; each VTU reads back
    with displacement and velocity, and the last one is the final field of fields.vtu."""
    import xml.etree.ElementTree as ET

    out = tmp_path / solver
    assert main(["run", "notched_strip", "--solver", solver, "--set", "harmonics=20", "--set", "t_end=3.2e-5",
                 "--every", "5", "--out", str(out), "--quiet"]) == 0
    sets = ET.parse(out / "fields.pvd").getroot().find("Collection").findall("DataSet")
    times = [float(d.get("timestep")) for d in sets]
    assert times == pytest.approx([0.0, 1.6e-5, 3.2e-5])
    import pyvista

    reader = pyvista.get_reader(str(out / "fields.pvd"))  # as ParaView opens it
    assert reader.number_time_points == 3 and reader.time_values == pytest.approx(times)
    reader.set_active_time_value(reader.time_values[-1])
    assert "displacement" in reader.read()[0].point_data
    frames = [meshio.read(out / d.get("file")) for d in sets]
    assert all({"displacement", "velocity"} <= set(f.point_data) and {"stress", "peps"} <= set(f.cell_data) for f in frames)
    assert all(np.isfinite(f.cell_data["stress"][0]).all() for f in frames)
    assert not frames[0].point_data["displacement"].any() and frames[2].point_data["displacement"].any()
    final = meshio.read(out / "fields.vtu")  # the frames in single precision
    for key in ("displacement", "velocity"):
        assert frames[2].point_data[key].dtype == np.float32
        assert np.allclose(frames[2].point_data[key], final.point_data[key], rtol=1e-6, atol=1e-6 * np.abs(final.point_data[key]).max())


def test_every_out_of_range_is_a_usage_error(tmp_path, capsys):
    assert main(["run", "dome", "--every", "201", "--out", str(tmp_path / "x")]) == 2
    assert "--every 201" in capsys.readouterr().err and not (tmp_path / "x").exists()


def test_the_fields_carry_the_stress_as_cartesian_tensors_alike_in_both_solvers(tmp_path):
    """The unnotched elastic strip at mid-span: the span stress of the top and bottom fibres
    (bending) and the vertical stress under the load, from each solver's fields.vtu (SMFEM: the
    moment-scheme element's centre, rotated from the element frame; the reference: the mean
    over the element's quadrature points). Measured: -7.26 / -7.30 MPa on top, 6.89 / 6.92 at
    the bottom, -0.93 / -1.05 MPa vertical under the 1 MPa load."""
    stress = {}
    for solver in ("smfem", "reference"):
        out = tmp_path / solver
        assert main(["run", "notched_strip", "--solver", solver, "--set", "plastic=false", "--set", "notch_depth=0",
                     "--set", "harmonics=40", "--set", "q=1e6", "--out", str(out), "--quiet"]) == 0
        m = meshio.read(out / "fields.vtu")
        s = m.cell_data["stress"][0].reshape(-1, 3, 3)
        assert np.abs(s - s.transpose(0, 2, 1)).max() <= 1e-9 * np.abs(s).max()
        c = m.points[m.cells[0].data].mean(axis=1)
        top, bottom = (np.argmin(np.hypot(c[:, 0] - 0.15, c[:, 2] - z)) for z in (0.1, 0.0))
        stress[solver] = (s[top, 0, 0], s[bottom, 0, 0], s[top, 2, 2])
    (top, bottom, vertical), ref = stress["smfem"], stress["reference"]
    assert top < 0 < bottom and vertical < 0
    assert top == pytest.approx(ref[0], rel=0.03) and bottom == pytest.approx(ref[1], rel=0.03)
    assert vertical == pytest.approx(ref[2], rel=0.2)


def test_solver_options_come_from_set_and_are_recorded(tmp_path, capsys):
    """A field of SMFEM's SolverOptions given as --set reaches the solver (bare words allowed)
    and summary.json records it; a bad value, or another solver's option, exits 2 with one line."""
    out = tmp_path / "sor"
    args = ["run", "thick_cylinder", "--set", "plastic=true", "--set", "t_end=4e-4", "--set", "iteration_matrix=sor",
            "--set", "anderson=0", "--out", str(out), "--quiet", "--no-fields", "--estimate", "off"]
    assert main(args) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["options"] == {"iteration_matrix": "sor", "anderson": 0}
    assert "block SOR" in summary["info"]["solve"]
    for bad, needle in ((["--set", "iteration_matrix=blah"], "one of auto, coupled, matrix-free, sor"),
                        (["--solver", "reference", "--set", "anderson=1"], "an option of smfem, not of reference")):
        capsys.readouterr()
        assert main(["run", "dome", *bad, "--out", str(tmp_path / "bad"), "--quiet"]) == 2
        err = capsys.readouterr().err
        assert needle in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "bad").exists()


def test_every_subcommands_help_is_printed():
    """argparse expands ``%`` in help texts only when asked for --help: a stray one fails there."""
    import argparse

    from smfem.cli import build_parser

    parser = build_parser()
    subparsers = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, sub in subparsers.choices.items():
        assert name in parser.format_help() and sub.format_help().startswith("usage: smfem " + name)
