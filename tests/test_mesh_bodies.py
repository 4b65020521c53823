"""Several bodies in one gmsh section (issue 56): physical surfaces that share no node may touch,
their faces physical curves ``'body.edge'`` joined by ``[[contact]]`` pairs. The example
``examples/rod_collision_unstructured.toml`` is the built-in ``rod_collision`` on such a section
(cases/sections/rod_collision.py; its 1-D answer at nu = 0: tests/test_rod_collision.py); a crack
in one body is still refused, and every mistake with bodies and pairs is one line, exit 2."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cases import get_case
from cases.bodies import pair_faces
from cases.msh_section import read_msh
from test_mesh_scene_files import run_scene
from test_msh_section import write

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "rod_collision_unstructured.toml"
TEXT = EXAMPLE.read_text()
MESH = ROOT / "cases" / "sections" / "rod_collision.msh"
#: what a solver reads of a Case, the section aside
FIELDS = ("body", "material", "loads", "supports", "probes", "params", "length", "cutouts", "initial_velocity",
          "wall", "symmetric", "axisymmetric", "regions", "contacts")
CONTACT = '[[contact]]                    # the two faces, touching at t = 0 (the gap is the geometry\'s)\n' \
          'face = "target.face"\nother = "striker.face"\nfriction = "friction"\n'


def test_the_example_is_the_builtin_scene_on_the_gmsh_section():
    builtin, case = get_case("rod_collision"), get_case(EXAMPLE)
    assert all(getattr(case, f) == getattr(builtin, f) for f in FIELDS)
    section, mapped = case.section, builtin.section
    assert set(section.edges) == set(mapped.edges) and set(section.regions) == set(mapped.regions)
    assert section.bounds == mapped.bounds
    # two bodies: each surface one piece of its own
    pieces = {name: set(section.pieces[ids].tolist()) for name, ids in section.regions.items()}
    assert all(len(p) == 1 for p in pieces.values()) and pieces["striker"] != pieces["target"]


@pytest.mark.parametrize("refine", [1, 2])
@pytest.mark.parametrize("order", [1, 2])
def test_the_examples_faces_meet_node_for_node(refine, order):
    """The pair's faces at z = 0, at every refinement and element order: each node of the
    target's face has the striker's node at its place (to gmsh's round-off along the curve,
    4e-17 m; gap 0), and the bodies touch nowhere else."""
    case = get_case(EXAMPLE, {"refine": refine})
    mesh = case.section.mesh(refine, order=order)
    pairing = pair_faces(mesh, case.contacts[0])
    assert len(pairing.face) == 5 * refine * order + 1
    assert np.allclose(mesh.x[pairing.face], mesh.x[pairing.other], rtol=0, atol=1e-16)
    assert np.all(pairing.gap == 0.0)
    assert np.all(np.isclose(pairing.normal, [0.0, -1.0]))
    touching = case.section.refined(refine).touching
    assert len(touching) == 10 * refine + 1 and np.all(case.section.refined(refine).x[touching][..., 1] == 0.0)


def test_the_kept_mesh_has_the_probe_nodes_and_two_pieces():
    section = read_msh(MESH)
    for point in ((0.0, 0.5), (0.0, 1.0)):
        assert np.min(np.hypot(*(section.x - point).T)) == 0.0
    assert len(np.unique(section.pieces)) == 2


def squares(tmp_path, joined: bool = False, b_left_on_a: bool = False) -> Path:
    """Two unit squares side by side, surfaces ``a`` ([0, 1]^2) and ``b`` ([1, 2] x [0, 1]),
    curves ``a.right`` and ``b.left`` on the line x = 1 between them: each its own nodes there
    (two bodies that touch), or ``joined`` (one piece); ``b_left_on_a`` puts ``b.left`` on a's
    edge."""
    a = [[0, 0], [1, 0], [1, 1], [0, 1]]
    if joined:
        points, quads, left = a + [[2, 0], [2, 1]], [[0, 1, 2, 3], [1, 4, 5, 2]], [[2, 1]]
    else:
        points, quads, left = a + [[1, 0], [2, 0], [2, 1], [1, 1]], [[0, 1, 2, 3], [4, 5, 6, 7]], [[7, 4]]
    if b_left_on_a:
        left = [[2, 1]]
    points = np.column_stack([np.asarray(points, float), np.zeros(len(points))])
    blocks = [("line", np.array([[1, 2]]), 1), ("line", np.array(left), 2), ("quad", np.array(quads), [3, 4])]
    return write(tmp_path / "squares.msh", points, blocks, names={"a.right": [1, 1], "b.left": [2, 1], "a": [3, 2],
                                                                 "b": [4, 2]})


SQUARES = """name = "squares"
body = "ring"
axisymmetric = true
[params]
dt = 1e-6
t_end = 2e-6
harmonics = 1
E = 2.1e11
nu = 0.3
rho = 7.8e3
tau_s = 1.7e8
layer_thickness = 1e-4
layer_stiffness = 1.0
[section]
kind = "mesh"
file = "{path}"
[[contact]]
face = "a.right"
other = "b.left"
[[probe]]
name = "p"
kind = "edge_mean"
field = "sigma"
component = ["n", "n"]
edge = "a.right"
"""


def test_two_bodies_that_touch_are_read_and_joined_by_a_pair(tmp_path):
    section = read_msh(squares(tmp_path))
    assert len(np.unique(section.pieces)) == 2
    assert len(section.touching) == 3  # the two corners and the mid-side at x = 1
    assert len(section.refined(2).touching) == 5
    case = get_case_text(tmp_path, SQUARES.format(path=tmp_path / "squares.msh"))
    pairing = pair_faces(case.section.mesh(1, order=2), case.contacts[0])
    assert np.all(pairing.gap == 0.0) and np.all(np.isclose(pairing.normal, [1.0, 0.0]))


def get_case_text(tmp_path, text):
    scene = tmp_path / "scene.toml"
    scene.write_text(text)
    return get_case(scene)


def example(text: str) -> str:
    return text.replace('file = "../cases/sections/rod_collision.msh"', f'file = "{MESH}"')


NO_CONTACT = example(TEXT.replace(CONTACT, "").replace("friction = 0.0\n", "")
                     .replace("layer_thickness = 1e-4", "#").replace("layer_stiffness = 1.0", "#"))
IMPACT = (ROOT / "examples" / "rod_impact_unstructured.toml").read_text().replace(
    'file = "../cases/sections/rod_impact.msh"', f'file = "{ROOT / "cases" / "sections" / "rod_impact.msh"}"')


@pytest.mark.parametrize("make, needle", [
    (lambda tmp: NO_CONTACT, "section.file: the bodies 'striker' and 'target' touch at (x1, x2) = (0.05, 0) where "
                             "no [[contact]] pair joins them"),
    (lambda tmp: SQUARES.format(path=squares(tmp, joined=True)),
     "contact[1]: contact pair a.right / b.left: the bodies 'a' and 'b' are one piece of the mesh"),
    (lambda tmp: SQUARES.format(path=squares(tmp, b_left_on_a=True)),
     "contact[1]: contact pair a.right / b.left: 'b.left' is not an edge of the body 'b'"),
    (lambda tmp: IMPACT.replace("[wall]", '[[contact]]\nface = "face"\nother = "free_end"\n\n[wall]'),
     "contact[1]: contact pair face / free_end: 'face' is not a face of one of the scene's bodies"),
    (lambda tmp: example(TEXT.replace('other = "striker.face"', 'other = "striker.end"')),
     "contact[1]: contact pair target.face / striker.end: the faces do not face each other"),
])
def test_a_mistake_with_the_bodies_of_a_mesh_is_one_line(tmp_path, capsys, make, needle):
    code, err = run_scene(tmp_path, make(tmp_path), capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and needle in err and "Traceback" not in err, err
    assert not (tmp_path / "scene").exists()
