"""Section meshes read from gmsh files (:mod:`cases.msh_section`): small meshes written with
meshio (gmsh itself is not needed), read back, refined, located in; every mesh a solver could
not use refused with one line."""

from __future__ import annotations

import math

import meshio
import numpy as np
import pytest

from cases.msh_section import MeshSection, SectionImportError, read_msh

#: quad9 node offsets on a block's node grid (corners counter-clockwise, mid-sides, centre)
OFF_I = np.array([0, 2, 2, 0, 1, 2, 1, 0, 1])
OFF_J = np.array([0, 0, 2, 2, 0, 1, 2, 1, 1])
#: field_data of the sample block: two curves, two surfaces
NAMES = {"bottom": [1, 1], "top": [2, 1], "left": [3, 2], "right": [4, 2]}


def block(nx=2, ny=2, order=1, x0=1.0, mapping=None):
    """An ``nx x ny`` grid of quad4 or quad9 on [x0, x0 + 2] x [0, 1] (or ``mapping`` of
    (s, t) in [0, 1]^2): points ``(n, 3)``, quadrilaterals, bottom and top lines (meshio order
    [a, b(, mid)]), and each element's column."""
    ni, nj = 2 * nx + 1, 2 * ny + 1  # a quad9 node grid; quad4 uses its even nodes
    s, t = np.meshgrid(np.linspace(0, 1, ni), np.linspace(0, 1, nj), indexing="ij")
    x, y = mapping(s, t) if mapping else (x0 + 2 * s, t)
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    i, j = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij"))
    nodes = 9 if order == 2 else 4
    quads = (2 * i[:, None] + OFF_I[:nodes]) * nj + 2 * j[:, None] + OFF_J[:nodes]
    k = np.arange(nx)
    ends = [[0, 2], [0, 2, 1]][order - 1]
    bottom = (2 * k[:, None] + ends) * nj
    top = bottom + nj - 1
    if order == 1:  # drop the nodes quad4 does not use: numbered compactly, as a file would be
        used = np.unique(quads)
        new = np.full(len(points), -1)
        new[used] = np.arange(len(used))
        points, quads, bottom, top = points[used], new[quads], new[bottom], new[top]
    return points, quads, bottom, top, i


def write(path, points, blocks, names=NAMES, fmt="gmsh22", binary=False):
    """Write ``blocks`` ``[(cell type, cells, physical tag(s))]`` to the gmsh file ``path``."""
    cells = [(kind, np.asarray(data)) for kind, data, _ in blocks]
    tags = [np.broadcast_to(np.asarray(tag, int), len(data)).copy() for _, data, tag in blocks]
    mesh = meshio.Mesh(points, cells, cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
                       field_data={n: np.array(v) for n, v in names.items()})
    meshio.write(path, mesh, file_format=fmt, binary=binary)
    return path


def groups(quads, bottom, top, column, order=1):
    """The blocks of :data:`NAMES`: curves bottom and top, surfaces left and right (by column)."""
    line, quad = ["line", "line3"][order - 1], ["quad", "quad9"][order - 1]
    return [(line, bottom, 1), (line, top, 2), (quad, quads, 3 + column)]


def sample(tmp_path, order=1, name="block.msh", **kw):
    """The 2 x 2 sample block with its groups."""
    points, *rest = block(order=order)
    return write(tmp_path / name, points, groups(*rest, order=order), **kw)


def annulus(s, t):
    """A quarter annulus, r in [1, 2], every node on its arc."""
    r, angle = 1 + s, t * math.pi / 2
    return r * np.cos(angle), r * np.sin(angle)


def curved(tmp_path, nx=2, ny=2):
    """The quarter annulus in quad9, its outer arc the curve ``outer``, one region."""
    points, quads, _, _, _ = block(nx, ny, 2, mapping=annulus)
    nj = 2 * ny + 1
    t = np.arange(ny)
    outer = (2 * nx) * nj + 2 * t[:, None] + np.array([0, 2, 1])
    return read_msh(write(tmp_path / "annulus.msh", points, [("line3", outer, 1), ("quad9", quads, 2)],
                          names={"outer": [1, 1], "ring": [2, 2]}))


def edge_area(x, elements) -> float:
    """Area inside the elements' quadratic edges (Green's theorem, exact by 3 Gauss points)."""
    g, w = np.polynomial.legendre.leggauss(3)
    total = 0.0
    for a, b, m in ((0, 1, 4), (1, 2, 5), (2, 3, 6), (3, 0, 7)):
        pa, pb, pm = x[elements[:, a]], x[elements[:, b]], x[elements[:, m]]
        d1, d2 = (pb - pa) / 2, (pa + pb) / 2 - pm
        for s, ws in zip(g, w):
            p, dp = pm + s * d1 + s * s * d2, d1 + 2 * s * d2
            total += ws * np.sum(p[:, 0] * dp[:, 1] - p[:, 1] * dp[:, 0]) / 2
    return total


def polygon_area(x, corners) -> float:
    """Shoelace area of the corner polygons."""
    p, q = x[corners], x[np.roll(corners, -1, axis=1)]
    return float(np.sum(p[..., 0] * q[..., 1] - q[..., 0] * p[..., 1]) / 2)


def element_edges(section, e):
    """The 4 counter-clockwise edges ``[a, mid, b]`` of elements ``e``: ``(len(e), 4, 3)``."""
    el = section.elements[e]
    return np.stack([el[:, [0, 1, 2, 3]], el[:, 4:8], el[:, [1, 2, 3, 0]]], axis=-1)


def test_quad4_block_reads(tmp_path):
    section = read_msh(sample(tmp_path))
    assert section.source_order == 1 and section.kind == "mesh"
    assert section.x.shape == (9 + 12 + 4, 2) and section.elements.shape == (4, 9)
    assert edge_area(section.x, section.elements) == pytest.approx(2.0, rel=1e-14)
    assert section.bounds == ((1.0, 3.0), (0.0, 1.0))
    assert {n: list(ids) for n, ids in section.regions.items()} == {"left": [0, 1], "right": [2, 3]}
    for name, y in (("bottom", 0.0), ("top", 1.0)):
        seg, owner = section.edges[name], section.edge_owner[name]
        assert seg.shape == (2, 3) and np.all(section.x[seg, 1] == y)
        # straight mid-sides, chained, counter-clockwise round the owner (outward to the right)
        assert np.allclose(section.x[seg[:, 1]], (section.x[seg[:, 0]] + section.x[seg[:, 2]]) / 2)
        assert np.all(seg[1:, 0] == seg[:-1, 2])
        assert np.sign(section.x[seg[0, 2], 0] - section.x[seg[0, 0], 0]) == (1 if y == 0 else -1)
        assert all((element_edges(section, [e])[0] == s).all(axis=1).any() for s, e in zip(seg, owner))


@pytest.mark.parametrize("fmt, binary", [("gmsh22", False), ("gmsh22", True), ("gmsh", False)])
def test_formats_keep_physical_names(tmp_path, fmt, binary):
    """MSH 2.2 ASCII and binary and MSH 4.1 give the same section, names and all."""
    reference = read_msh(sample(tmp_path, order=2))
    points, quads, bottom, top, column = block(order=2)
    blocks = [("line3", bottom, 1), ("line3", top, 2),
              ("quad9", quads[column == 0], 3), ("quad9", quads[column == 1], 4)]
    kw = {}
    if fmt == "gmsh":  # MSH 4.1: every block an entity, which meshio takes from the nodes
        dim_tags = np.tile([2, 3], (len(points), 1))
        for dim_tag, cells in (([2, 4], quads[column == 1]), ([1, 1], bottom), ([1, 2], top)):
            dim_tags[cells.ravel()] = dim_tag
        kw = {"point_data": {"gmsh:dim_tags": dim_tags}}
    cells = [(kind, data) for kind, data, _ in blocks]
    tags = [np.full(len(data), tag) for _, data, tag in blocks]
    mesh = meshio.Mesh(points, cells, cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
                       field_data={n: np.array(v) for n, v in NAMES.items()}, **kw)
    path = tmp_path / f"block_{fmt}_{binary}.msh"
    meshio.write(path, mesh, file_format=fmt, binary=binary)
    section = read_msh(path)
    if fmt == "gmsh22":
        assert section == reference and hash(section) == hash(reference)
    # MSH 4.1 lists the nodes by entity: the same geometry, numbered otherwise
    assert np.array_equal(section.x[section.elements], reference.x[reference.elements])
    for name, seg in reference.edges.items():
        assert np.array_equal(section.x[section.edges[name]], reference.x[seg])
        assert np.array_equal(section.edge_owner[name], reference.edge_owner[name])
    assert {n: ids.tolist() for n, ids in section.regions.items()} == {"left": [0, 1], "right": [2, 3]}
    assert section.path == str(path)


MSH41_TWO_GROUPS = """$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
3
1 1 "bottom"
1 2 "loaded"
2 3 "body"
$EndPhysicalNames
$Entities
0 1 1 0
1 0 0 0 1 0 0 2 1 2 0
1 0 0 0 1 1 0 1 3 0
$EndEntities
$Nodes
2 4 1 4
1 1 0 2
1
2
0 0 0
1 0 0
2 1 0 2
3
4
1 1 0
0 1 0
$EndNodes
$Elements
2 2 1 2
1 1 1 1
1 1 2
2 1 3 1
2 1 2 3 4
$EndElements
"""


def test_msh41_curve_in_two_groups(tmp_path):
    """An MSH 4.1 entity in two physical groups is in both (meshio's ``gmsh:physical`` keeps
    the first only; its ``cell_sets`` keep both)."""
    path = tmp_path / "two.msh"
    path.write_text(MSH41_TWO_GROUPS)
    section = read_msh(path)
    assert np.array_equal(section.edges["bottom"], section.edges["loaded"])
    assert section.edges["bottom"].tolist() == [[0, 4, 1]] and list(section.regions) == ["body"]


def test_curved_quad9_refines_on_the_edge_curve(tmp_path):
    section = curved(tmp_path)
    area = edge_area(section.x, section.elements)
    assert area == pytest.approx(3 * math.pi / 4, rel=1e-3)
    errors = []
    for k in (2, 4, 8):
        fine = section.refined(k)
        # the refined map is the same map: the same area, to round-off
        assert edge_area(fine.x, fine.elements) == pytest.approx(area, rel=1e-13)
        x1, el1, _ = fine.at_order(1)
        errors.append(area - polygon_area(x1, el1))
        # each outer segment's 2k + 1 refined nodes lie on the parabola through its 3 nodes
        seg, fine_seg = section.edges["outer"], fine.edges["outer"].reshape(-1, k, 3)
        s = np.linspace(-1, 1, 2 * k + 1)[:, None]
        for parent, children in zip(seg, fine_seg):
            a, m, b = section.x[parent]
            parabola = m + s * (b - a) / 2 + s * s * ((a + b) / 2 - m)
            nodes = np.concatenate([children[:, :2].ravel(), children[-1:, 2]])
            assert np.allclose(fine.x[nodes], parabola, rtol=0, atol=1e-14)
        # every node shared between neighbours once: node count of a (2 m k + 1)^2 grid
        assert len(fine.x) == (4 * k + 1) ** 2
    slope = np.polyfit(np.log([2, 4, 8]), np.log(errors), 1)[0]
    assert slope == pytest.approx(-2, abs=0.1)


def test_refine_carries_edges_and_regions(tmp_path):
    section = read_msh(sample(tmp_path, order=2))
    assert section.refined(1) is section
    for bad in (0, -1, 1.5, True, "2"):
        with pytest.raises(ValueError):
            section.refined(bad)
    k = 3
    fine = section.refined(k)
    assert fine.elements.shape == (4 * k * k, 9) and fine.source_order == 2
    assert edge_area(fine.x, fine.elements) == pytest.approx(2.0, rel=1e-14)
    for name, ids in section.regions.items():
        assert np.array_equal(fine.regions[name], np.sort(fine.regions[name]))
        assert len(fine.regions[name]) == k * k * len(ids)
        assert np.all((fine.x[fine.elements[fine.regions[name], 8], 0] < 2) == (name == "left"))
    for name, seg in section.edges.items():
        fine_seg, owner = fine.edges[name], fine.edge_owner[name]
        assert fine_seg.shape == (k * len(seg), 3) and np.all(fine_seg[1:, 0] == fine_seg[:-1, 2])
        assert fine_seg[0, 0] == seg[0, 0] and fine_seg[-1, 2] == seg[-1, 2]
        edges = element_edges(fine, owner)
        assert np.all(np.any(np.all(edges == fine_seg[:, None, :], axis=2), axis=1))
    assert np.allclose(fine.refined(2).x[: len(fine.x)], fine.x)


def test_clockwise_elements_are_reordered(tmp_path):
    for order in (1, 2):
        points, quads, bottom, top, column = block(order=order)
        mirror = [[0, 3, 2, 1], [0, 3, 2, 1, 7, 6, 5, 4, 8]][order - 1]
        flipped = quads.copy()
        flipped[[0, 3]] = quads[[0, 3]][:, mirror]
        blocks = groups(flipped, bottom, top, column, order)
        section = read_msh(write(tmp_path / f"cw{order}.msh", points, blocks))
        assert section == read_msh(sample(tmp_path, order=order))


def test_at_order(tmp_path):
    section = read_msh(sample(tmp_path, order=2))
    x, elements, edges = section.at_order(2)
    assert x is section.x and elements is section.elements and edges["top"][0] is section.edges["top"]
    x1, el1, edges1 = section.at_order(1)
    corners = np.unique(section.elements[:, :4])
    assert len(corners) == 9 < len(section.x) and np.array_equal(x1, section.x[corners])
    assert np.array_equal(np.unique(el1), np.arange(9))
    assert np.array_equal(x1[el1], section.x[section.elements[:, :4]])
    for name, (seg, owner) in edges1.items():
        assert seg.shape == (2, 2) and np.array_equal(x1[seg], section.x[section.edges[name][:, [0, 2]]])
        assert owner is section.edge_owner[name]
    with pytest.raises(ValueError):
        section.at_order(3)


def test_locate_round_trips(tmp_path):
    section = curved(tmp_path).refined(2)
    rng = np.random.default_rng(1)
    e = rng.integers(0, len(section.elements), 300)
    ref = rng.uniform(-0.9, 0.9, (300, 2))
    a, b = ref.T
    lag = [np.stack([s * (s - 1) / 2, 1 - s * s, s * (s + 1) / 2], axis=-1) for s in (a, b)]
    N = np.stack([lag[0][:, i] * lag[1][:, j] for i, j in zip(OFF_I, OFF_J)], axis=-1)
    p = np.einsum("pn,pnc->pc", N, section.x[section.elements[e]])
    found, found_ref = section.locate(p[:, 0], p[:, 1])
    assert np.array_equal(found, e) and np.allclose(found_ref, ref, rtol=0, atol=1e-10)
    # a node and a point a round-off outside (on the boundary, in [-1, 1]^2), a point between
    # the curved edge and its chord (in its element, outside the element's corner polygon)
    seg, owner = section.edges["outer"][0], section.edge_owner["outer"][0]
    corner = section.x[section.elements[0, 0]] * (1 - 1e-12)
    outer = section.x[seg[1]] * (1 + 1e-9)
    bulge = section.x[seg[1]] * (1 - 1e-3)
    el, xi = section.locate(*np.transpose([corner, outer, bulge]))
    assert np.all(np.abs(xi) <= 1) and np.isclose(np.abs(xi[1]).max(), 1)
    assert el[1] == el[2] == owner and 0.9 < np.abs(xi[2]).max() < 1
    el, xi = section.locate(np.array([[1.5]]), 0.2)  # arrays broadcast and are flattened
    assert el.shape == (1,) and xi.shape == (1, 2)
    with pytest.raises(SectionImportError, match=r"point \(x1, x2\) = \(0.5, 0.5\) lies outside"):
        section.locate(0.5, 0.5)


def test_unused_nodes_dropped_and_ring_axis(tmp_path):
    points, quads, bottom, top, column = block(x0=0.0)
    points = np.concatenate([points, [[5.0, 5.0, 0.0]]])  # in no element
    points[quads[0, 0], 0] = -1e-13  # on the axis, but for round-off
    section = read_msh(write(tmp_path / "axis.msh", points, groups(quads, bottom, top, column)))
    assert len(section.x) == 9 + 12 + 4 and section.bounds[0] == (0.0, 2.0)


def test_no_physical_surfaces_is_one_body(tmp_path):
    points, quads, bottom, _, _ = block()
    section = read_msh(write(tmp_path / "body.msh", points, [("line", bottom, 1), ("quad", quads, 0)],
                             names={"bottom": [1, 1]}))
    assert list(section.regions) == ["body"] and np.array_equal(section.regions["body"], np.arange(4))


def squares(tmp_path, name, points, quads, kind="quad", body="prism"):
    """Read a few quad4 elements with no groups (the refusals below)."""
    points = np.column_stack([np.asarray(points, float), np.zeros(len(points))])
    return read_msh(write(tmp_path / name, points, [(kind, np.asarray(quads), 0)], names={}), body=body)


UNIT = [[0, 0], [1, 0], [1, 1], [0, 1]]


def refusal(tmp_path, case):
    """Write the mesh of refusal ``case`` and read it."""
    points, quads, bottom, top, column = block()
    blocks = groups(quads, bottom, top, column)
    if case == "missing":
        return read_msh(tmp_path / "missing.msh")
    if case == "garbage":
        (tmp_path / "garbage.msh").write_text("$MeshFormat\nnot a mesh\n")
        return read_msh(tmp_path / "garbage.msh")
    if case in ("triangle", "triangle6", "quad8", "tetra"):
        cells = {"triangle": [[0, 1, 2]], "triangle6": [[0, 1, 2, 3, 4, 5]], "quad8": [list(range(8))],
                 "tetra": [[0, 1, 2, 3]]}[case]
        blocks.append((case, np.array(cells), 3))
    if case == "mixed":
        p9, q9, *_ = block(order=2)
        points = np.concatenate([points, p9 + [5, 0, 0]])
        blocks.append(("quad9", q9 + len(points) - len(p9), 3))
    if case == "z":
        points[4, 2] = 0.1
    if case == "r < 0":
        points[:, 0] -= 2
    if case == "diagonal":
        blocks.append(("line", quads[:1, [0, 2]], 1))
    if case == "empty surface":
        return read_msh(write(tmp_path / "m.msh", points, blocks, names=NAMES | {"ghost": [9, 2]}))
    if case == "empty curve":
        return read_msh(write(tmp_path / "m.msh", points, blocks, names=NAMES | {"nothing": [8, 1]}))
    if case == "no surface":
        blocks[2] = ("quad", quads, np.where(column == 0, 3, 0))
        return read_msh(write(tmp_path / "m.msh", points, blocks, names={"left": [3, 2]}))
    if case == "two surfaces":
        blocks.append(("quad", quads[:1], 4))
    if case == "dart":
        return squares(tmp_path, "dart.msh", [[0, 0], [2, 0], [0.3, 0.3], [0, 2]], [[0, 1, 2, 3]])
    if case == "bow tie":
        return squares(tmp_path, "bow.msh", [[0, 0], [1, 0], [0, 1], [1, 1]], [[0, 1, 2, 3]])
    if case == "crack":
        return squares(tmp_path, "crack.msh", UNIT + [[1, 0], [2, 0], [2, 1], [1, 1]],
                       [[0, 1, 2, 3], [4, 5, 6, 7]])
    if case == "crack in one piece":  # joined at the bottom, the top node duplicated
        return squares(tmp_path, "slit.msh", [[0, 0], [1, 0], [2, 0], [2, 1], [1, 1], [1, 1], [0, 1]],
                       [[0, 1, 4, 6], [1, 2, 3, 5]])
    if case == "hanging across bodies":  # two separate pieces touching along x = 1, not node for node
        return squares(tmp_path, "bodies.msh", UNIT + [[1, 0], [2, 0], [2, 0.5], [1, 0.5], [2, 1], [1, 1]],
                       [[0, 1, 2, 3], [4, 5, 6, 7], [7, 6, 8, 9]])
    if case == "hanging":
        return squares(tmp_path, "hanging.msh",
                       [[0, 0], [1, 0], [1, 2], [0, 2], [2, 0], [2, 1], [2, 2], [1, 1]],
                       [[0, 1, 2, 3], [1, 4, 5, 7], [7, 5, 6, 2]])
    if case == "overlap":
        return squares(tmp_path, "overlap.msh", UNIT + [[0.3, 0.8], [0.3, 0.2]],
                       [[0, 1, 2, 3], [1, 2, 4, 5]])
    if case == "split mid-side":  # quad9 neighbours with a mid-side node each on their edge
        points, quads, bottom, top, column = block(nx=2, ny=1, order=2)
        points = np.concatenate([points, points[quads[1, 7]][None]])
        quads[1, 7] = len(points) - 1
        return read_msh(write(tmp_path / "split.msh", points, groups(quads, bottom, top, column, 2)))
    return read_msh(write(tmp_path / "m.msh", points, blocks))


REFUSALS = {
    "missing": "no such file",
    "garbage": "cannot be read as a gmsh mesh",
    "triangle": r"has 1 triangles: make quadrilaterals \(gmsh: Mesh.RecombineAll = 1",
    "triangle6": "has 1 6-node triangles",
    "quad8": "quad8.*SecondOrderIncomplete = 0",
    "tetra": "has 1 tetra cells",
    "mixed": "mixes 4 quad and 4 quad9",
    "z": r"is off the x-y plane",
    "r < 0": r"reaches r < 0 at node \(x1, x2\) = \(-1, 0\)",
    "diagonal": "line of physical curve 'bottom' .* is not an element edge",
    "empty surface": "physical surface 'ghost' .* has no quadrilaterals",
    "empty curve": "physical curve 'nothing' .* has no lines",
    "no surface": "2 elements are in no physical surface",
    "two surfaces": "physical surfaces 'left' and 'right'",
    "dart": "element 0 .* is degenerate or inverted",
    "bow tie": "element 0 .* is degenerate or inverted",
    "crack": r"element edges at \(x1, x2\) = \(1, [01]\) are not connected \(a crack or duplicated",
    "crack in one piece": r"edges at \(x1, x2\) = \(1, 1\) are not connected \(a crack or duplicated nodes\): merge",
    "hanging": r"corner at \(1, 1\) .* \(a hanging node\)",
    "hanging across bodies": r"corner at \(1, 0.5\) .* of another body: where two bodies touch, mesh their faces node",
    "overlap": "elements overlap along the edge",
    "split mid-side": r"elements on the edge from \(2, 0\) to \(2, 1\) have different mid-side nodes",
}


@pytest.mark.parametrize("case", REFUSALS)
def test_refusals_are_one_line(tmp_path, case):
    with pytest.raises(SectionImportError, match=REFUSALS[case]) as info:
        refusal(tmp_path, case)
    message = str(info.value)
    assert "\n" not in message and message.startswith(str(tmp_path)) and ": " in message


def test_ring_refusal_is_a_prism(tmp_path):
    """The section refused as a ring (r < 0) is a valid prism section."""
    points, quads, bottom, top, column = block(x0=-1.0)
    path = write(tmp_path / "left.msh", points, groups(quads, bottom, top, column))
    assert read_msh(path, body="prism").bounds[0] == (-1.0, 1.0)
    with pytest.raises(ValueError):
        read_msh(path, body="torus")


def test_section_is_a_value(tmp_path):
    a, b = read_msh(sample(tmp_path)), read_msh(sample(tmp_path, name="again.msh"))
    assert a == b and hash(a) == hash(b) and a.path != b.path
    assert a != a.refined(2) and isinstance(a.refined(2), MeshSection)
