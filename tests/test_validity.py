"""A run checks whether it stays inside the small-strain, small-rotation model (smfem.runs.validity)."""

import json
import math
from types import SimpleNamespace

import meshio
import numpy as np
import pytest

from cases import get_case
from smfem.cli import main
from smfem.runs.validity import LIMITS, check, field_gradients, smallest_dimension


def _box_field(u_of_x) -> meshio.Mesh:
    """A 2 x 2 x 2 hexahedral block with the point displacement ``u_of_x(points)``."""
    g = np.linspace(0.0, 1.0, 3)
    pts = np.array([[x, y, z] for z in g for y in g for x in g])
    idx = lambda i, j, k: i + 3 * j + 9 * k
    hexes = [[idx(i, j, k), idx(i + 1, j, k), idx(i + 1, j + 1, k), idx(i, j + 1, k),
              idx(i, j, k + 1), idx(i + 1, j, k + 1), idx(i + 1, j + 1, k + 1), idx(i, j + 1, k + 1)]
             for k in range(2) for j in range(2) for i in range(2)]
    return meshio.Mesh(pts, [("hexahedron", np.array(hexes))], point_data={"displacement": u_of_x(pts)})


def test_the_gradient_of_a_linear_field_is_recovered_on_every_cell():
    G = np.array([[1e-3, 2e-3, 0.0], [-4e-3, 0.5e-3, 1e-3], [0.0, 3e-3, -2e-3]])
    mesh = _box_field(lambda x: x @ G.T + 0.1)
    grads = field_gradients(mesh)
    assert grads.shape == (8, 3, 3) and np.allclose(grads, G, atol=1e-12)


def test_a_rigid_rotation_is_a_rotation_not_a_strain():
    a = 0.2  # rad, about z, linearised: u = w x x
    case = SimpleNamespace(probes=(), section=get_case("rod_impact").section)
    mesh = _box_field(lambda x: np.column_stack([-a * x[:, 1], a * x[:, 0], 0 * x[:, 0]]))
    v = check(case, SimpleNamespace(history={}, mesh=mesh))
    assert v["rotation"] == pytest.approx(a) and v["strain"] < 1e-12
    assert not v["valid"] and "rotation" in v["exceeded"]


def test_the_thinnest_dimension_of_each_scene():
    # a shell's thickness, a wall's, the strip's height (its one-element width does not count), a rod's radius
    assert smallest_dimension(get_case("dome")) == pytest.approx(0.41)
    assert smallest_dimension(get_case("thick_cylinder")) == pytest.approx(1.0)
    assert smallest_dimension(get_case("notched_strip")) == pytest.approx(0.1)
    assert smallest_dimension(get_case("rod_impact")) == pytest.approx(0.05)


@pytest.mark.parametrize("sets, valid, exceeded", [
    (["plastic=true"], True, []),  # the paper's load
    (["plastic=true", "q=5e8"], False, ["strain"]),  # ten times it: 54 % plastic strain
])
def test_a_run_says_whether_it_is_inside_the_model(tmp_path, capsys, sets, valid, exceeded):
    args = ["run", "thick_cylinder", "--out", str(tmp_path), "--quiet"]
    for s in sets:
        args += ["--set", s]
    assert main(args) == 0
    v = json.loads((tmp_path / "summary.json").read_text())["validity"]
    err = capsys.readouterr().err
    assert v["valid"] is valid and set(exceeded) <= set(v["exceeded"])
    assert v["from"] == "probes and fields" and v["limits"] == LIMITS
    if valid:
        assert v["strain"] < LIMITS["strain"] and "outside the small-strain model" not in err
    else:
        assert v["strain"] > 0.3 and len([x for x in err.splitlines() if "outside the small-strain model" in x]) == 1


def test_the_collapsed_dome_is_outside_the_model(tmp_path, capsys):
    """5000 psi on the plastic dome: the apex moves many thicknesses."""
    assert main(["run", "dome", "--set", "plastic=true", "--set", "q=5000", "--out", str(tmp_path), "--quiet",
                 "--no-fields"]) == 0
    v = json.loads((tmp_path / "summary.json").read_text())["validity"]
    assert not v["valid"] and "displacement_ratio" in v["exceeded"] and v["from"].startswith("probes only")
    assert v["displacement_ratio"] > 1 and math.isfinite(v["largest_displacement"])
    assert "outside the small-strain model" in capsys.readouterr().err


def test_the_report_runs_table_marks_a_run_outside_the_model():
    from reports.tables import inside_model

    assert inside_model({"valid": True, "exceeded": []}) == "yes" and inside_model(None) == ""
    marked = inside_model({"valid": False, "exceeded": ["strain", "rotation"], "strain": 0.54, "rotation": 0.5})
    assert marked == "no: strain 0.54, rotation 0.5"
