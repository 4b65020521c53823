"""Reference meshes of a mesh section (:class:`cases.msh_section.MeshSection`): its 9-node
quadrilaterals as they are (the axisymmetric 2D model and the harmonic model), or swept round
the axis (a ring) or along the length (a prism) into 27-node hexahedra (3D), or, a ring's plane
strain (a section the same at every z: a stack of rectangles), its lowest row swept round the
axis into the 9-node quadrilaterals of an annulus (2D).

Every node of a hexahedron is the image of its reference position under the section element's
own 9-node map times the sweep, so curved section edges stay curved. ``refine = k`` splits each
section element k x k (:func:`cases.section_mesh.section_mesh`): the 3D model cannot halve a
mesh section as it halves a block's counts, so its section is the 2D one. The circumference of a
ring gets ``N_THETA * refine`` elements, a prism's span elements as long as the section's
median element. Break points (load patches, cut-outs, probes) along x3 are element boundaries.

Named edges are found by the section's own segments: a boundary facet lies on edge ``name``
when the section points of its vertices are the two ends of one of that edge's segments and its
element was made from that segment's element (two bodies that touch have a face each at the
same points). The section's pieces (the bodies of a scene of several, :mod:`cases.bodies`)
share no node, and neither do their elements here (:func:`pieces`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from skfem import ElementHex2, ElementQuad2

from cases.geometry import RING
from cases.msh_section import shape
from cases.params import UnsupportedCase
from cases.section_mesh import section_mesh

from .frames import AXISYMMETRIC, PLANE_STRAIN, SOLID, to_cartesian


def section_elements(case):
    """The mesh section's own 9-node mesh at the case's refinement (each element split refine x
    refine), in scikit-fem's ``ElementQuad2`` node order."""
    return section_mesh(case.section, case.mesh_scale, order=2)


def check_sweepable(case, rep: str, section) -> None:
    """Refuse the representations a mesh section has no form in, in one line."""
    if rep not in (AXISYMMETRIC, SOLID):
        plane_strain_row(case, section)


def plane_strain_row(case, section) -> np.ndarray:
    """The section elements of a ring's plane-strain form: those on the section's lowest x2
    (each, swept round the axis, is an annulus sector); refused in one line unless every
    element is a rectangle aligned with the axes whose nodes stand in three rows of x1 and
    three of x2 (so that the section is the same at every x2: what plane strain assumes), and
    those on the lowest x2 span the section's x1 once."""
    if case.body != RING:
        raise UnsupportedCase(f"reference solver: {case.name}: a prism's mesh section has no plane-strain 2D form; "
                              "use dim=3")
    X = section.x[section.elements]  # (n_el, 9, 2)
    scale = np.abs(section.x).max()
    key = np.round(X / (1e-9 * scale)).astype(np.int64)
    rows = np.sum(np.diff(np.sort(key, axis=1), axis=1) != 0, axis=1) + 1  # (n_el, 2): distinct x1, x2
    level = key[:, :, 1].min(axis=1)  # each element's lowest x2
    width = X[:, :, 0].max(axis=1) - X[:, :, 0].min(axis=1)
    bottom = np.flatnonzero(level == level.min())
    # the lowest row's elements span as much x1 as those at every other height
    same = all(np.isclose(width[bottom].sum(), width[level == z].sum(), rtol=1e-9) for z in np.unique(level))
    if np.any(rows != 3) or not same:
        raise UnsupportedCase(f"reference solver: {case.name}: a mesh section has a plane-strain 2D form only where "
                              "it is a stack of rectangles aligned with r and z, the same at every z; use dim=3")
    return bottom


def annulus_nodes(section, row: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Node coordinates ``(2, n_elements, 9)`` (scikit-fem's ``ElementQuad2`` order) of the
    plane-strain ring: each section element of ``row`` (:func:`plane_strain_row`) over its x1
    (its three node rows: quadratic in x1 as the section element is) times each interval of the
    ``theta`` nodes; elements ordered theta interval by theta interval."""
    x1 = section.x[section.elements[row], 0]  # (n_row, 9): three nodes at each of its three radii
    r = np.column_stack([x1.min(axis=1), np.median(x1, axis=1), x1.max(axis=1)])
    ref = ElementQuad2.doflocs  # (9, 2) in [0, 1]^2: (along x1, round the axis)
    xi = ref[:, 0]
    lagrange = np.column_stack([2 * (xi - 0.5) * (xi - 1), -4 * xi * (xi - 1), 2 * xi * (xi - 0.5)])  # (9, 3)
    radius = r @ lagrange.T  # (n_row, 9)
    angle = theta[:-1, None] + np.diff(theta)[:, None] * ref[None, :, 1]  # (n_theta, 9)
    R = np.broadcast_to(radius[None], (len(angle),) + radius.shape)
    A = np.broadcast_to(angle[:, None, :], R.shape)
    return np.array([R * np.cos(A), R * np.sin(A)]).reshape(2, -1, 9)


def median_size(section) -> float:
    """The section elements' median size (diagonal / sqrt 2): a prism's element length along x3."""
    X = section.x[section.elements]
    return float(np.median(np.linalg.norm(X[:, 2] - X[:, 0], axis=1) / np.sqrt(2)))


def element_nodes(case, section, x3: np.ndarray | None) -> np.ndarray:
    """Node coordinates of the reference elements, ``(dim, n_elements, 9 | 27)`` in scikit-fem's
    reference order: the section's 9-node elements (``x3`` None), or each swept over every
    interval of the ``x3`` nodes, round the axis (a ring) or along the length (a prism)."""
    X = section.x[section.elements]  # (n_el, 9, 2) in scikit-fem's ElementQuad2 node order
    if x3 is None:
        return X.transpose(2, 0, 1)
    ref = ElementHex2.doflocs  # (27, 3) in [0, 1]^3
    N = shape(2 * ref[:, 0] - 1, 2 * ref[:, 1] - 1)[0]  # (27, 9): the section element's map
    points = np.einsum("pn,enc->epc", N, X)  # (n_el, 27, 2)
    along = x3[:-1, None] + np.diff(x3)[:, None] * ref[None, :, 2]  # (n_x3, 27)
    x1 = np.broadcast_to(points[None, :, :, 0], (len(along),) + points.shape[:2])
    x2 = np.broadcast_to(points[None, :, :, 1], x1.shape)
    a = np.broadcast_to(along[:, None, :], x1.shape)
    out = np.array([x1 * np.cos(a), x1 * np.sin(a), x2] if case.body == RING else [a, x1, x2])
    return out.reshape(3, -1, 27)


def axis_tags(case, section, x3: np.ndarray | None) -> np.ndarray | None:
    """Where a ring's section reaches the axis and is swept round it (``x3``), the angle of each
    element node on the axis as a tag, ``(n_elements, 27)`` (0 off the axis, else 1 + the index
    of its angle among the half-steps of ``x3``, the full circle's last angle its first): the
    mesh keeps the nodes at one axis point apart by angle and ties them as one unknown
    (:mod:`reference_fem.ties`). None where nothing is on the axis."""
    if x3 is None or case.body != RING:
        return None
    ref = ElementHex2.doflocs
    N = shape(2 * ref[:, 0] - 1, 2 * ref[:, 1] - 1)[0]  # (27, 9)
    r = np.einsum("pn,en->ep", N, section.x[section.elements][:, :, 0])  # (n_el, 27)
    on_axis = np.abs(r) <= 1e-9 * np.abs(section.x).max()
    if not on_axis.any():
        return None
    half_steps = 2 * (len(x3) - 1)
    index = 2 * np.arange(len(x3) - 1)[:, None] + np.round(2 * ref[None, :, 2]).astype(np.int64)  # (n_x3, 27)
    if np.isclose(x3[-1] - x3[0], 2 * np.pi):
        index = index % half_steps
    tags = np.where(on_axis[None], 1 + index[:, None, :], 0)  # (n_x3, n_el, 27)
    return tags.reshape(-1, 27)


def element_parents(section, x3: np.ndarray | None) -> np.ndarray:
    """The section element each element of :func:`element_nodes` is made from, ``(n_elements,)``."""
    return np.tile(np.arange(len(section.elements)), 1 if x3 is None else len(x3) - 1)


def pieces(section) -> np.ndarray:
    """The connected piece of the section each of its elements is in, ``(n_elements,)``:
    elements sharing a node are of one piece; the bodies of a scene of several share none."""
    n_el, n_nodes = section.elements.shape[0], len(section.x)
    el = np.repeat(np.arange(n_el), section.elements.shape[1])
    graph = sp.coo_matrix((np.ones(el.size), (el, n_el + section.elements.ravel())),
                          shape=(n_el + n_nodes,) * 2)
    return connected_components(graph, directed=False)[1][:n_el]


def edge_facets(case, rep: str, mesh, section, facets: np.ndarray, edge: str,
                parent: np.ndarray | None = None) -> np.ndarray:
    """Those of boundary ``facets`` of a reference ``mesh`` (representation ``rep``) that lie on
    the mesh section's edge ``edge``; ``section``: the section's quadratic mesh the reference
    mesh was made from; ``parent`` (n_elements,): the section element of each element of
    ``mesh`` (:func:`element_parents`), when given a facet must also be of its segment's element
    (a face of another body at the same points is not on the edge)."""
    seg, owner = section.edge_segments(edge)
    scale = 1e-7 * np.abs(section.x).max()
    if rep == PLANE_STRAIN:
        return _annulus_edge_facets(mesh, section, facets, edge, parent, seg, owner, scale)
    key = lambda p: [tuple(k) for k in np.round(np.asarray(p) / scale).astype(np.int64)]  # noqa: E731
    ends = {frozenset(pair): o for pair, o in zip(zip(key(section.x[seg[:, 0]]), key(section.x[seg[:, -1]])),
                                                 np.asarray(owner).tolist())}
    corners = mesh.p[:, mesh.facets[:, facets].T]  # (dim, n_facets, n_vertices)
    xc = to_cartesian(case, rep, corners.reshape(corners.shape[0], -1))
    x1, x2 = (np.hypot(xc[0], xc[1]), xc[2]) if case.body == RING else (xc[1], xc[2])
    points = key(np.column_stack([x1, x2]))
    n = corners.shape[2]
    # a facet on the axis of a ring swept round it is a line (:mod:`reference_fem.ties`): on no edge
    line = np.all(np.abs(x1.reshape(-1, n)) <= scale, axis=1) if case.body == RING and rep == SOLID else \
        np.zeros(len(facets), bool)
    on = [frozenset(points[i * n:(i + 1) * n]) in ends and not line[i] for i in range(len(facets))]
    if parent is not None:
        element = mesh.f2t[0, facets]  # a boundary facet's one element
        on = [hit and ends[frozenset(points[i * n:(i + 1) * n])] == parent[element[i]] for i, hit in enumerate(on)]
    found = facets[np.array(on, bool)]
    if found.size == 0:
        raise ValueError(f"reference solver: edge {edge!r} has no boundary facets")
    return found


def _annulus_edge_facets(mesh, section, facets, edge, parent, seg, owner, scale) -> np.ndarray:
    """:func:`edge_facets` of a ring's plane-strain annulus: a facet round the axis at radius r
    of an element made from section element e lies on the edge where one of the edge's segments
    runs along x2 at x1 = r and belongs to e (the annulus has no facets of the edges along x1:
    they are its plane)."""
    along = np.abs(section.x[seg[:, 0], 0] - section.x[seg[:, -1], 0]) <= scale
    wanted = {(int(o), int(k)) for o, k in zip(np.asarray(owner)[along],
                                               np.round(section.x[seg[along, 0], 0] / scale).astype(np.int64))}
    corners = mesh.p[:, mesh.facets[:, facets]]  # (2, n_vertices, n_facets)
    r = np.round(np.hypot(corners[0], corners[1]) / scale).astype(np.int64)
    element = parent[mesh.f2t[0, facets]]
    on = (r[0] == r[-1]) & np.array([(int(e), int(k)) in wanted for e, k in zip(element, r[0])], bool)
    found = facets[on]
    if found.size == 0:
        raise ValueError(f"reference solver: edge {edge!r} has no boundary facets")
    return found
