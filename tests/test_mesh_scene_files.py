"""Scene files with a gmsh section: what a user gets wrong is one line and exit 2, from the
command line (the reader's own checks of a mesh: tests/test_msh_section.py)."""

from pathlib import Path

import meshio
import numpy as np
import pytest

from smfem.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
FLYWHEEL = (EXAMPLES / "flywheel.toml").read_text()
MESH = (EXAMPLES.parent / "cases" / "sections" / "flywheel.msh").resolve()


def run_scene(tmp_path, text: str, capsys, name: str = "scene") -> tuple[int, str]:
    scene = tmp_path / f"{name}.toml"
    scene.write_text(text)
    code = main(["run", str(scene), "--quiet", "--no-fields", "--estimate", "off", "--set", "t_end=2e-5", "--out",
                 str(tmp_path / name)])
    return code, capsys.readouterr().err


def with_mesh(text: str, path) -> str:
    return text.replace('file = "../cases/sections/flywheel.msh"', f'file = "{path}"')


@pytest.mark.parametrize("change, needle", [
    (lambda t: t.replace('edge = "rim_top"', 'edge = "rim_side"'), "rim_side"),
    (lambda t: with_mesh(t, "/nonexistent/flywheel.msh"), "flywheel.msh"),
    (lambda t: with_mesh(t, MESH.with_suffix(".py")), "gmsh mesh file"),
    (lambda t: t + '\n[[region]]\nname = "bronze"\nE = 1.1e11\n', "bronze"),
    (lambda t: t + '\n[[region]]\nname = "steel"\ns_range = [0.1, 0.2]\n', "s_range"),
    (lambda t: t.replace("point = [0.3, 0.03, 0.0]", "point = [0.3, 0.05, 0.0]"), "outside the section"),
    (lambda t: t.replace('[section]', '[section]\ns = { breaks = [0, 1], counts = [1] }'), "section.s"),
])
def test_a_mistake_in_a_mesh_scene_is_one_line(tmp_path, capsys, change, needle):
    code, err = run_scene(tmp_path, with_mesh(change(FLYWHEEL), MESH), capsys)  # a changed file line stays
    assert code == 2 and len(err.strip().splitlines()) == 1 and needle in err and "Traceback" not in err, err
    assert not (tmp_path / "scene").exists()


def test_a_mesh_of_triangles_is_refused_naming_the_file(tmp_path, capsys):
    points = np.array([[0.1, 0.0, 0.0], [0.2, 0.0, 0.0], [0.2, 0.1, 0.0], [0.1, 0.1, 0.0]])
    mesh = meshio.Mesh(points, [("triangle", np.array([[0, 1, 2], [0, 2, 3]]))])
    path = tmp_path / "tri.msh"
    meshio.write(path, mesh, file_format="gmsh22", binary=False)
    capsys.readouterr()  # meshio's own warnings while writing the test's file
    code, err = run_scene(tmp_path, with_mesh(FLYWHEEL, path), capsys)
    assert code == 2 and "tri.msh" in err and "triangle" in err and len(err.strip().splitlines()) == 1, err


def test_a_region_of_the_mesh_gets_its_own_material(tmp_path, capsys):
    """The flywheel's one region, from the file, of half the density: the first steps' response
    is inertia's (u ~ F t^2 / 2 m), so about twice the deflection."""
    import pandas as pd

    light = with_mesh(FLYWHEEL, MESH) + '\n[[region]]\nname = "steel"\nrho = 3.9e3\n'
    assert run_scene(tmp_path, light, capsys, "light")[0] == 0
    assert run_scene(tmp_path, with_mesh(FLYWHEEL, MESH), capsys, "steel")[0] == 0
    peak = {n: np.abs(pd.read_csv(tmp_path / n / "history.csv")["rim_uz_0"].to_numpy()).max() for n in ("light", "steel")}
    assert 1.7 < peak["light"] / peak["steel"] < 2.3
