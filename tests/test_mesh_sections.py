"""Mesh sections (:mod:`cases.msh_section`, read from gmsh files) in SMFEM: the patch test on
unstructured, distorted meshes with both section elements, the manufactured motion on an
L-shaped section of two regions converging at each element's order, and a mesh that cannot be
coarsened refused in one line."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse.linalg as sla
from test_msh_section import write

from cases import verification_mesh
from cases.geometry import PRISM, RING
from cases.msh_section import read_msh
from cases.params import UnsupportedCase
from reports.verification import EXACT_IN_TIME
from smfem.runs.registry import SMFEM, solve
from smfem import elements
from smfem.assembly import assemble, weighted_elasticity
from smfem.constitutive import isotropic_D
from smfem.probes import locate

D = isotropic_D(2.1e11, 0.3)
#: where each body's patch lies: a ring's at r in [1, 2]
SHIFT = {RING: (1.0, 0.0), PRISM: (0.0, 0.0)}
NAMES = {"boundary": [1, 1], "body": [2, 2]}


def pentagon_in_a_square(seed=0, move=0.2):
    """The unit square as a pentagon in a ring of five quadrilaterals, each polygon split round
    its centroid (:func:`cases.verification_mesh.subdivide`: 25 elements; the pentagon's centre
    has valence 5, its corners 3), the interior nodes then moved at random by up to ``move``
    times the shortest element side at each: ``(x (n, 2), quads (m, 4))``."""
    angle = np.radians(90 + 72 * np.arange(5))
    pentagon = 0.5 + 0.15 * np.column_stack([np.cos(angle), np.sin(angle)])
    points = np.concatenate([[(0, 0), (1, 0), (1, 1), (0, 1), (0.5, 1)], pentagon])
    a, b, c, d, top, p0, p1, p2, p3, p4 = range(10)
    polygons = [(d, a, p2, p1), (a, b, p3, p2), (b, c, p4, p3), (c, top, p0, p4), (top, d, p1, p0),
                (p0, p1, p2, p3, p4)]
    x, quads, _ = verification_mesh.subdivide(points, polygons)
    sides = quads[:, [0, 1, 1, 2, 2, 3, 3, 0]].reshape(-1, 2)
    shortest = np.full(len(x), np.inf)
    length = np.linalg.norm(x[sides[:, 1]] - x[sides[:, 0]], axis=1)
    np.minimum.at(shortest, sides.ravel(), np.repeat(length, 2))
    inside = np.all((x > 1e-12) & (x < 1 - 1e-12), axis=1)
    rng = np.random.default_rng(seed)
    return x + inside[:, None] * move * rng.uniform(-1, 1, x.shape) * shortest[:, None], quads


def rhombi():
    """A decagon tiled by ten rhombi (parallelograms) round a centre of valence 5, five
    corners of valence 3 round it, scaled to unit width: ``(x (16, 2), quads (10, 4))``."""
    u = [np.array([math.cos(a), math.sin(a)]) for a in np.radians(72 * np.arange(5))]
    x, quads = [np.zeros(2)], []

    def node(p):
        found = [i for i, q in enumerate(x) if np.allclose(q, p)]
        if not found:
            x.append(p)
        return found[0] if found else len(x) - 1

    for j in range(5):  # five wide rhombi round the centre, then a narrow one at each inner corner
        quads.append([0, node(u[j]), node(u[j] + u[(j + 1) % 5]), node(u[(j + 1) % 5])])
    for j in range(5):
        a, left, right = u[j], u[j - 1], u[(j + 1) % 5]
        quads.append([node(a), node(a + left), node(a + left + right), node(a + right)])
    x = np.array(x)
    return (x - x.min(axis=0)) / np.ptp(x[:, 0]), np.array(quads)


def quadratic(x, quads, lines, bow=0.0):
    """quad9 and line3 cells (gmsh's node order) of a quad4 mesh: mid-sides at the sides'
    middles, centres at the corners' mean, the mid-sides of the boundary ``lines`` (counter-
    clockwise) moved outward by ``bow`` times their side's length (curved boundary edges)."""
    sides = quads[:, [0, 1, 1, 2, 2, 3, 3, 0]].reshape(-1, 2)

    def code(pairs):
        return np.sort(pairs, axis=1) @ [len(x), 1]

    keys, first, side_of = np.unique(code(sides), return_index=True, return_inverse=True)
    a, b = x[sides[first, 0]], x[sides[first, 1]]  # a boundary side runs counter-clockwise
    outward = (b - a)[:, ::-1] * [1, -1]
    mid = (a + b) / 2 + bow * np.isin(keys, code(lines))[:, None] * outward
    n = len(x)
    points = np.concatenate([x, mid, x[quads].mean(axis=1)])
    centres = n + len(keys) + np.arange(len(quads))
    cells = np.column_stack([quads, n + side_of.reshape(-1, 4), centres])
    return points, cells, np.column_stack([lines, n + np.searchsorted(keys, code(lines))])


def patch_file(path, kind: str, body: str, order: int):
    """The patch ``kind`` ("distorted", "curved": its boundary edges bowed, "rhombi") on
    ``body``'s span as a gmsh file of ``order`` (1: quad4, 2: quad9), its boundary the physical
    curve ``boundary``."""
    x, quads = rhombi() if kind == "rhombi" else pentagon_in_a_square()
    x = x + SHIFT[body]
    lines = verification_mesh.boundary_lines(quads)
    if order == 1:
        blocks = [("line", lines, 1), ("quad", quads, 2)]
    else:
        x, quads, lines = quadratic(x, quads, lines, bow=0.1 if kind == "curved" else 0.0)
        blocks = [("line3", lines, 1), ("quad9", quads, 2)]
    return write(path, np.column_stack([x, np.zeros(len(x))]), blocks, names=NAMES)


def patch_error(mesh, element, body: str) -> float:
    """The patch test on a section mesh: the nodes of its edge ``boundary`` follow a linear field
    of constant strain (prism, k = 0: any; ring, harmonic 0, symmetric family: u_r = a r,
    u_z = c + d z), the others follow from ``K u = 0``; the largest error relative to the field."""
    X = mesh.x[mesh.elements]
    ops = element.operators(X, body, 0.3)
    integrals = np.zeros((len(X), 2, 2))
    integrals[:, 0, 0], integrals[:, 1, 1] = (1.0, 0.0) if body == RING else (1.0, 1.0)
    K = assemble(ops.stiffness(0.0, weighted_elasticity(D, integrals)), mesh.elements, mesh.n_nodes)
    K = K.tocsr()
    x1, x2 = mesh.x.T
    if body == PRISM:
        exact = np.column_stack([2e-3 * x1 + 1e-3 * x2, -1e-3 * x1 + 3e-3 * x2,
                                 1e-3 * x1 - 2e-3 * x2]).ravel()
    else:
        exact = np.column_stack([2e-3 * x1, 1e-3 + 3e-3 * x2, 0 * x1]).ravel()
    free = np.zeros((mesh.n_nodes, 3), bool)
    free[:, :3 if body == PRISM else 2] = True  # a ring's harmonic 0, symmetric family: no u_theta
    free[mesh.edge_nodes("boundary")] = False
    free = free.ravel()
    u = np.where(free, 0.0, exact)
    u[free] = sla.spsolve(K[free][:, free].tocsc(), -(K[free] @ u))
    return float(np.abs(u - exact).max() / np.abs(exact).max())


def interior_valences(section) -> set[int]:
    """How many elements share each corner node off the boundary."""
    count = np.bincount(section.elements[:, :4].ravel())
    boundary = np.unique(np.concatenate([seg for seg in section.edges.values()]))
    corners = np.setdiff1d(np.unique(section.elements[:, :4]), boundary)
    return set(count[corners].tolist())


@pytest.mark.parametrize("element, body, kind", [
    ("moment4", PRISM, "distorted"), ("moment4", PRISM, "rhombi"), ("moment4", RING, "rhombi"),
    ("quad9", PRISM, "distorted"), ("quad9", RING, "distorted"),
    ("quad9", PRISM, "curved"), ("quad9", RING, "curved"), ("quad9", RING, "rhombi"),
])
def test_the_patch_test_passes_on_unstructured_mesh_sections(tmp_path, element, body, kind):
    """Constant strain reproduced to round-off on meshes read from gmsh files, as they are and
    split 2 x 2: a pentagon in a ring of quadrilaterals split round their centroids (corners of
    valence 3 and 5), interior nodes moved by up to 20 % of the shortest side at each; quad9
    files with straight mid-sides, or with boundary edges bowed by 10 % of their length. The
    ring's moment scheme takes sqrt(g) = |J| r at the centre, exact on parallelograms only
    (tests/test_element.py): a tiling by rhombi, corners of valence 3 and 5 too."""
    element = elements.get(element)
    section = read_msh(patch_file(tmp_path / f"{kind}.msh", kind, body, element.mesh_order), body)
    assert {3, 5} <= interior_valences(section)
    for split in (1, 2):
        error = patch_error(section.mesh(split, order=element.mesh_order), element, body)
        assert error < 1e-12, (split, error)


def test_the_rings_moment_scheme_on_distorted_elements_is_consistent_at_second_order(tmp_path):
    """Not a patch test: on the distorted pentagon mesh the ring's moment scheme misses the
    constant strain (|J| r at the centre integrates r exactly only where J is constant), and
    the miss falls as h^2 as its elements, split k x k, tend to parallelograms."""
    section = read_msh(patch_file(tmp_path / "distorted.msh", "distorted", RING, 1), RING)
    errors = [patch_error(section.mesh(k), elements.MOMENT4, RING) for k in (1, 2, 4)]
    assert errors[0] > 1e-3
    assert abs(np.log2(errors[1] / errors[2]) - 2) < 0.2, errors


@pytest.fixture(scope="module")
def l_sections(tmp_path_factory):
    """The manufactured scenes' L, read from its gmsh file, per body."""
    folder = tmp_path_factory.mktemp("l")
    return {body: read_msh(verification_mesh.write(folder / f"l_{body}.msh", body), body)
            for body in (RING, PRISM)}


def test_the_l_is_unstructured_non_convex_and_its_motion_vanishes_on_its_edges(l_sections):
    """The L's mesh has corners of valence 3 and 5 and two regions; the motion is zero on both
    physical curves, not inside, and has the square's dependence on x3."""
    from cases import manufactured as mf
    from cases import verification

    for body, section in l_sections.items():
        assert {3, 5} <= interior_valences(section) and set(section.regions) == {"leg", "foot"}
        mesh = section.mesh(2)
        case = verification_mesh.build(body, section, EXACT_IN_TIME)
        index = case.material_index(mesh.element_st_centres(), region_elements=mesh.regions)
        assert set(index.tolist()) == {1, 2}
        on_edges = np.unique(np.concatenate([mesh.edge_nodes(name) for name in ("outer", "notch")]))
        x1, x2, x3 = case.probes[0].point
        for mine, square in zip(verification_mesh.motion(body), verification.motion(body)):
            mine, square = mf.numeric(str(mine)), mf.numeric(str(square))
            assert np.abs(mine(mesh.x[on_edges, 0], mesh.x[on_edges, 1], 0.7, 0.0)).max() < 1e-12
            assert np.isclose(mine(x1, x2, x3, 0.0) * square(x1, x2, 0.7, 0.0),
                              mine(x1, x2, 0.7, 0.0) * square(x1, x2, x3, 0.0), rtol=1e-12, atol=0)
            assert mine(x1, x2, x3, 0.0) != 0
    # the re-entrant corner is a node; the notch above and right of it is outside
    section = l_sections[RING]
    assert np.any(np.all(np.isclose(section.x, (1.5, 0.5)), axis=1))
    with pytest.raises(UnsupportedCase, match="outside the section"):
        section.locate(1.75, 0.75)


@pytest.mark.parametrize("body, element, levels, theory, a", [
    # the default run checks each element's order on one body: moment4's on the ring, quad9's on
    # the prism (the ring's quad9 on a mesh section: tests/test_reference_axis.py, through the
    # axis); the other two ladders run with -m slow
    (RING, "moment4", (1, 2, 4), 2, 0.3), pytest.param(PRISM, "moment4", (1, 2, 4), 2, 0.3, marks=pytest.mark.slow),
    # quad9 is pre-asymptotic up to refine 4 (orders 3.3-3.4 on this L, 4.2 and 3.5 on the
    # mapped square): its finest pair is refine 4 and 8, the material kept constant along x3
    # (the coupled system at refine 8 takes 45 s; the coupling is the moment4 ladders')
    pytest.param(RING, "quad9", (1, 2, 4, 8), 3, 0.0, marks=pytest.mark.slow), (PRISM, "quad9", (1, 2, 4, 8), 3, 0.0),
])
def test_the_manufactured_motion_on_the_l_converges_at_the_elements_order(l_sections, body, element,
                                                                         levels, theory, a):
    """SMFEM's L2 error over the body at the end of five steps of t^2 (exact in time: the mesh's
    error alone), six harmonics, refined by splitting every element k x k: it falls at every
    level, and the observed order of the finest pair is the element's within 0.2 (moment4: 2,
    as on the mapped square in tests/test_manufactured.py; quad9: 3)."""
    errors = []
    for refine in levels:
        params = {**EXACT_IN_TIME, "harmonics": 6, "refine": refine, "element": element, "a": a}
        run = solve(SMFEM, verification_mesh.build(body, l_sections[body], params))
        assert run.converged
        errors.append(run.info["error_l2"])
    assert np.all(np.diff(errors) < 0), errors
    assert abs(np.log2(errors[-2] / errors[-1]) - theory) < 0.2, errors


def test_a_probe_is_found_where_a_far_elements_extended_map_folds(l_sections):
    """Newton's inversion runs in every element at once; on the L split 2 x 2 one element's
    bilinear map, extended to the clip at (-2, -2), has det J = 0 exactly there (it raised
    LinAlgError before)."""
    mesh = l_sections[RING].mesh(2)
    e, xi, eta = locate(mesh, elements.MOMENT4, (1.25, 0.25))
    N = elements.MOMENT4.shape_functions(np.array([xi]), np.array([eta]))[0]
    assert np.allclose(N @ mesh.x[mesh.elements[e]], (1.25, 0.25), atol=1e-12)


@pytest.mark.parametrize("params, scale", [({"coarsen": 2}, "0.5"),
                                           ({"refine": 3, "coarsen": 2}, "1.5")])
def test_a_mesh_section_is_not_coarsened(l_sections, params, scale):
    """A mesh section is refined by a whole factor only: coarsen = 2, or refine / coarsen not a
    whole number, is refused in one line before anything is solved."""
    case = verification_mesh.build(RING, l_sections[RING], {**EXACT_IN_TIME, **params})
    with pytest.raises(UnsupportedCase) as refused:
        solve(SMFEM, case)
    message = str(refused.value)
    assert "\n" not in message and f"cannot be coarsened or scaled by {scale}" in message
