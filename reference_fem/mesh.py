"""Meshes of the case geometry: curved quadratic quadrilaterals (2D) and hexahedra (3D).

Every mesh is a union of structured blocks in a parameter space. Each node of a quadratic
element (vertices, edge and face midpoints, centre) is the image of its parametric position
under the block's exact geometric map, so arcs and spherical surfaces are interpolated
quadratically, not by chords. Cut-outs and the notch are holes: elements whose centre lies in
a cut-out are not generated.

Resolution (``refine`` = ``case.params['refine']`` multiplies every refinable count)
----------------------------------------------------------------------------------
- section axes: the paper's element counts (``case.section``) in 2D, half of them (rounded,
  at least 1) in 3D, because one quadratic element spans about two of the paper's bilinear ones;
  axes marked not refinable (one element across a plane-strain width) keep one element;
- circumference of a ring that is not axisymmetric: ``N_THETA * refine`` elements (64, a
  multiple of 8 so that the 45 degree patch and cut-out limits are nodes), or the case's
  ``theta_elements`` when it sets one (:func:`theta_step`);
- span of a prism: elements as long as the section grid's finest refinable element (before
  break points split it);
- a solid of revolution with an axis (3D dome, rod): an O-grid disk (a square centre block and
  four outer blocks) replaces the polar grid, so there is no degenerate element on the axis;
  its radial density follows the section's axis-direction count.
Break points are inserted where cut-outs, material regions, load patches and displacement
probes begin or end, so these are element boundaries or nodes.

Grading (``grading`` = beta > 1, for truths): a cut-out's limit inside the body is a
re-entrant corner line (the cut-outs' corners, the notch root). Every segment between break
points that ends on such a line gets its nodes at ``xi^beta`` of its length, measured from
that end (from both ends, symmetrically, when both are such lines); the element count is that
of the uniform mesh, so a graded mesh costs the same per step, but its smallest element is
``n^(beta - 1)`` times shorter (n elements in the segment).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

import numpy as np
from scipy.spatial import cKDTree
from skfem import ElementHex2, ElementQuad2, MeshHex1, MeshHex2, MeshQuad1, MeshQuad2
from skfem.io.meshio import HEX_MAPPING
from skfem.mapping import MappingIsoparametric

from cases.params import UnsupportedCase
from cases.geometry import RING

from . import swept, ties
from .frames import AXISYMMETRIC, PLANE_STRAIN, SOLID, in_intervals, representation, section_of, x3_of

#: elements around the circumference of a (non-axisymmetric) ring at refine = 1: the
#: circumferential direction dominates the error of the thick cylinder, in 2D and in 3D
N_THETA = 64
#: multiplier of the paper's section counts, per dimension
SECTION_SCALE = {2: 1.0, 3: 0.5}
#: half-width of the O-grid's centre square, as a fraction of the disk radius
OGRID_CORE = 0.4


#: tolerance of the inverse isoparametric map, in reference coordinates
INVF_TOL = 1e-10
#: elements tried for a point (nearest centres first) by :meth:`MeshHex2Tied.element_finder`, and
#: how far from the point (relative to the mesh's size) an element's nearest image may be
FINDER_CANDIDATES = 32
FINDER_FIRST = 4
INSIDE_TOL = 1e-8


class _Mapping(MappingIsoparametric):
    """Isoparametric mapping whose inverse stops at :data:`INVF_TOL`, and whose inverse
    Jacobian and shape functions are kept for the points last asked for.

    scikit-fem's default (1e-12) lies below round-off for thin curved elements far from the
    origin (the 3D dome: 0.2 in thick at 22 in), where Newton then stalls. A basis asks for the
    inverse Jacobian once per shape function, at the same points: scikit-fem computes it again
    each time (81 times for a 27-node vector element); a facet basis inverts the map twice, for
    its points and for their normals, in the same elements. Each entry of the map and of its
    Jacobian evaluates every shape function and its gradient again (a 27-node hexahedron's
    Jacobian: 243 evaluations where 27 give it): here they are evaluated once per points
    (:meth:`_local`) and summed node by node in scikit-fem's order, so the sums are its own.
    """

    def invF(self, x, tind=None, newton_max_iters=50, newton_tol=INVF_TOL):
        last = getattr(self, "_last_invF", None)
        if last is None or last[0] is not x or not np.array_equal(last[1], tind) or last[2] != newton_tol:
            last = self._last_invF = (x, tind, newton_tol, self._inverse(x, tind, newton_max_iters, newton_tol))
        return last[3]

    def _inverse(self, x, tind, newton_max_iters, newton_tol):
        return super().invF(x, tind, newton_max_iters, newton_tol)

    def invDF(self, X, tind=None):
        last = getattr(self, "_last_invDF", None)
        if last is None or last[0] is not X or last[1] is not tind:
            # the arguments are kept with it, so their identities stand for their values
            last = self._last_invDF = (X, tind, super().invDF(X, tind))
        return last[2]

    def _local(self, element, X, n: int):
        """``element``'s first ``n`` shape functions and their gradients at the reference points
        ``X`` (``lbasis(X, k)``'s two parts, lists over ``k``), kept for the points last asked
        for."""
        last = getattr(self, "_last_local", None)
        if last is None or last[0] is not element or last[1] is not X or last[2] != n:
            # the points are kept with them, so their identity stands for their values
            values = [element.lbasis(X, k) for k in range(n)]
            last = (element, X, n, [v[0] for v in values], [v[1] for v in values])
            self._last_local = last
        return last[3], last[4]

    def _sum(self, nodes, element, X, i, j=None):
        """Entry ``i`` of the map (``j`` None) or ``(i, j)`` of its Jacobian, on the elements (or
        facets) whose nodes are ``nodes`` (n_functions, n): ``sum_k p[i, nodes[k]] phi_k``,
        over ``k`` in scikit-fem's order."""
        phi, dphi = self._local(element, X, nodes.shape[0])
        p = self.mesh.doflocs
        out = np.zeros((nodes.shape[1], X.shape[-1]))
        for k in range(nodes.shape[0]):
            out += p[i, nodes[k]][:, None] * (phi[k] if j is None else dphi[k][j])
        return out

    def _cell_nodes(self, tind):
        t = self.mesh.dofs.element_dofs
        return t if tind is None else t[:, tind]

    def _facet_nodes(self, find):
        facets = self.mesh.facets
        if len(self.mesh.dofs.edge_dofs) > 0:
            facets = np.vstack((facets, self.mesh.dofs.edge_dofs[0, self.mesh.f2e]))
        if len(self.mesh.dofs.facet_dofs) > 0:
            facets = np.vstack((facets, self.mesh.dofs.facet_dofs))
        return facets if find is None else facets[:, find]

    def Fmap(self, i, X, tind=None):
        return self._sum(self._cell_nodes(tind), self.elem, X, i)

    def _J(self, i, j, X, tind=None):
        return self._sum(self._cell_nodes(tind), self.elem, X, i, j)

    def bndmap(self, i, X, find=None):
        return self._sum(self._facet_nodes(find), self.bndelem, X, i)

    def bndJ(self, i, j, X, find=None):
        return self._sum(self._facet_nodes(find), self.bndelem, X, i, j)


class _AxisMapping(_Mapping):
    """:class:`_Mapping` of a mesh with hexahedra degenerate on the axis (:class:`MeshHex2Tied`):
    its inverse takes Newton's steps by the Jacobian's pseudo-inverse, which on the axis face
    (a line: one direction of the Jacobian vanishes) moves along the other two, and it stops at
    the step tolerance without raising; the caller checks how near the point it came."""

    def _inverse(self, x, tind, newton_max_iters, newton_tol):
        X = np.zeros(x.shape) + 0.5
        for _ in range(newton_max_iters):
            J = np.moveaxis(self.DF(X, tind), (0, 1), (-2, -1))  # (n_elements, n_points, dim, dim)
            dX = np.moveaxis(np.einsum("...ij,...j->...i", np.linalg.pinv(J), np.moveaxis(x - self.F(X, tind), 0, -1)), -1, 0)
            X = np.clip(X + dX, 0.0, 1.0)
            if np.abs(dX).max() < newton_tol:
                break
        return X


class _Curved:
    """Mixin: meshes whose isoparametric mapping is :class:`_Mapping`."""

    def _mapping(self):
        if not hasattr(self, "_cached_mapping"):
            self._cached_mapping = _Mapping(self, self.elem(), self.bndelem)
        return self._cached_mapping


@dataclass(repr=False)
class MeshQuad2Curved(_Curved, MeshQuad2):
    """:class:`skfem.MeshQuad2` that can locate points (for ``probes``).

    scikit-fem's quadratic 2D meshes have no element finder; searching the straight-sided
    vertex mesh and inverting the curved map in the found element is exact for points inside
    the chord polygon, which includes every mesh node.
    """

    def element_finder(self, mapping=None):
        vertices = MeshQuad1(np.ascontiguousarray(self.p[:, : self.nvertices]), self.t)
        find = vertices.element_finder()
        centres = vertices.p[:, vertices.t].mean(axis=1)

        def finder(x, y, _search_all=False):
            try:
                return find(x, y)
            except ValueError:  # a point on a curved edge can fall a round-off outside the chords
                return np.array([_one(find, centres, xi, yi) for xi, yi in zip(np.atleast_1d(x), np.atleast_1d(y))])

        return finder


def _one(find, centres: np.ndarray, x: float, y: float) -> int:
    """The element of one point: found, or else the one with the nearest centre."""
    try:
        return int(find(np.array([x]), np.array([y]))[0])
    except ValueError:
        return int(np.argmin(np.hypot(centres[0] - x, centres[1] - y)))


@dataclass(repr=False)
class MeshHex2Curved(_Curved, MeshHex2):
    """:class:`skfem.MeshHex2` with the tolerant inverse mapping."""


@dataclass(repr=False)
class MeshHex2Tied(MeshHex2Curved):
    """:class:`MeshHex2Curved` whose nodes at one point of the axis are one unknown
    (:mod:`reference_fem.ties`): ``ties`` (n_nodes,), the node each node is one with."""

    ties: np.ndarray | None = None

    def _mapping(self):
        if not hasattr(self, "_cached_mapping"):
            self._cached_mapping = _AxisMapping(self, self.elem(), self.bndelem)
        return self._cached_mapping

    def element_finder(self, mapping=None):
        """The element of each point: scikit-fem's finder splits the vertex mesh into
        tetrahedra, which are flat where a hexahedron is degenerate on the axis; here the
        elements with the nearest centres are tried, each by inverting its curved map (clipped
        to the element), and the one whose image of that is nearest the point is taken, if it
        is the point within round-off."""
        mapping = self._mapping() if mapping is None else mapping
        tree = cKDTree(self.doflocs[:, self.dofs.element_dofs[-1]].T)  # the centre nodes
        candidates = min(FINDER_CANDIDATES, self.nelements)
        size = np.abs(self.doflocs).max()

        def holder(point, near) -> int | None:
            """The first of the elements ``near`` that holds ``point``, or None."""
            at = point[:, None, None] + np.zeros((1, len(near), 1))
            miss = np.linalg.norm(mapping.F(mapping.invF(at, tind=near), tind=near)[:, :, 0] - point[:, None], axis=0)
            return int(near[np.argmin(miss)]) if miss.min() <= INSIDE_TOL * size else None

        def finder(x, y, z, _search_all=False):
            points = np.array([x, y, z], float).reshape(3, -1)
            found = np.empty(points.shape[1], np.int64)
            for k, point in enumerate(points.T):
                near = tree.query(point, candidates)[1]
                # the nearest few first: the point is almost always in one of them
                hit = holder(point, near[:FINDER_FIRST]) if FINDER_FIRST < len(near) else None
                hit = hit if hit is not None else holder(point, near)
                if hit is None and not _search_all:
                    hit = holder(point, np.arange(self.nelements))
                if hit is None:
                    raise ValueError("Point is outside of the mesh.")
                found[k] = hit
            return found

        return finder


@dataclass(frozen=True)
class Block:
    """A structured box of elements in a parameter space.

    Attributes
    ----------
    axes : node coordinates along each parametric direction, one 1-D array per direction
    to_mesh : map of parametric points, shape ``(len(axes), n)``, to mesh coordinates
        ``(dim, n)``
    """

    axes: tuple[np.ndarray, ...]
    to_mesh: Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class RefMesh:
    """A mesh of one case, its representation (see :mod:`reference_fem.frames`) and the element
    counts per mesh direction (``'elements'``: the total after removing holes)."""

    mesh: MeshQuad2 | MeshHex2
    rep: str
    counts: dict
    #: a mesh section's own quadratic mesh at the case's refinement (its named edges), else None
    section: object = None
    #: with ``section``: the section element each element was made from, ``(n_elements,)`` (its
    #: named edges' owners and regions: the bodies of a scene of several)
    parent: np.ndarray | None = None


def build_mesh(case, grading: float = 1.0) -> RefMesh:
    """Mesh ``case`` in the representation its ``dim`` parameter asks for; ``grading`` (at
    least 1, 1 = uniform) grades it toward the re-entrant corner lines (module docstring)."""
    if not grading >= 1.0:
        raise ValueError(f"grading must be at least 1, not {grading!r}")
    rep = representation(case)
    if case.section.kind == "mesh":
        return _mesh_section(case, rep)
    dim = 3 if rep == SOLID else 2
    scale = SECTION_SCALE[dim] * case.mesh_scale
    sec = case.section
    s_extra, t_extra, x3_extra = _breaks(case, rep)
    s_sing, t_sing, x3_sing = corner_lines(case) if grading > 1.0 else ((), (), ())
    s_nodes = axis_nodes(sec.s, scale, s_extra, Grading(s_sing, grading))
    t_nodes = axis_nodes(sec.t, scale, t_extra, Grading(t_sing, grading))
    x3_grading = Grading(x3_sing, grading)
    if case.body == RING and rep != AXISYMMETRIC:
        x3_nodes = _span_nodes(0.0, ring_span(case, rep), x3_extra, theta_step(case), x3_grading)
    elif case.body != RING:
        # the section grid's own finest element, not one a break point cut short: a 0.1 mm
        # notch would otherwise make 3000 elements along a 0.3 m span
        h = min(np.diff(axis_nodes(a, scale)).min() for a in (sec.s, sec.t) if a.refinable)
        x3_nodes = _span_nodes(0.0, case.length, x3_extra, h, x3_grading)
    else:
        x3_nodes = None

    if rep == AXISYMMETRIC:
        blocks = [Block((s_nodes, t_nodes), lambda p: np.array(sec.to_x(p[0], p[1])))]
        counts = {"s": len(s_nodes) - 1, "t": len(t_nodes) - 1}
    elif rep == PLANE_STRAIN:
        blocks, counts = _plane_blocks(case, s_nodes, t_nodes, x3_nodes)
    elif case.body == RING and _axis_direction(sec) is not None and case.params.get("mirror"):
        raise UnsupportedCase(f"reference solver: {case.name}: mirror: a solid of revolution that reaches the axis "
                              "has no half mesh here (its O-grid is whole)")
    elif case.body == RING and _axis_direction(sec) is not None and (case.axisymmetric or not (case.cutouts or case.loads)):
        # the O-grid has no node lines at given angles: fine where no cut-out or load patch needs them
        blocks, counts = _ogrid_blocks(sec, s_nodes, t_nodes)
    elif case.body == RING:
        def ring(p):
            x1, x2 = sec.to_x(p[0], p[1])
            return np.array([x1 * np.cos(p[2]), x1 * np.sin(p[2]), x2])

        blocks = [Block((s_nodes, t_nodes, x3_nodes), ring)]
        counts = {"s": len(s_nodes) - 1, "t": len(t_nodes) - 1, "theta": len(x3_nodes) - 1}
    else:
        def slab(p):
            x1, x2 = sec.to_x(p[0], p[1])
            return np.array([p[2], x1, x2])

        blocks = [Block((s_nodes, t_nodes, x3_nodes), slab)]
        counts = {"s": len(s_nodes) - 1, "t": len(t_nodes) - 1, "x3": len(x3_nodes) - 1}

    def keep(x):
        return ~_in_cutouts(case, rep, x)

    mesh = assemble_blocks(blocks, keep)
    return RefMesh(mesh, rep, dict(counts, elements=mesh.nelements))


def ring_span(case, rep: str) -> float:
    """The angle a 3D ring's mesh spans: 2 pi, or pi for the case's ``mirror`` half (refused in
    one line where the half is not the whole's mirror image, :class:`UnsupportedCase`)."""
    if not case.params.get("mirror"):
        return 2 * np.pi
    if case.body != RING or rep != SOLID:
        raise UnsupportedCase(f"reference solver: {case.name}: mirror is a 3D ring's half (dim=3 on a ring)")
    if not case.symmetric or case.wall is not None:
        raise UnsupportedCase(f"reference solver: {case.name}: mirror needs loads and material symmetric about "
                              "theta = 0 and no wall")
    outside = [p.name for p in case.probes if p.kind == "point" and np.sin(p.point[2]) < -1e-12]
    if outside:
        raise UnsupportedCase(f"reference solver: {case.name}: probe {outside[0]!r} lies outside the mirror half "
                              "0 <= theta <= pi")
    return np.pi


def theta_step(case) -> float:
    """The longest element round a ring in 3D (rad): ``2 pi / (N_THETA * refine)``, or over the
    case's ``theta_elements`` when it sets one."""
    return 2 * np.pi / (case.params.get("theta_elements") or N_THETA * case.mesh_scale)


def _mesh_section(case, rep: str) -> RefMesh:
    """A mesh section's reference mesh (:mod:`reference_fem.swept`): its 9-node elements, or
    swept into 27-node hexahedra over ``N_THETA * refine`` intervals (or ``theta_elements``) round a ring, or along a
    prism in elements as long as the section's median one, or (a ring in plane strain) its lowest row swept into
    an annulus over as many intervals; x3 break points are nodes."""
    section = swept.section_elements(case)
    swept.check_sweepable(case, rep, section)
    if rep == PLANE_STRAIN:  # a ring's annulus: the lowest row of the section swept round the axis
        row = swept.plane_strain_row(case, section)
        theta = _span_nodes(0.0, ring_span(case, rep), _breaks(case, rep)[2], theta_step(case))
        x = swept.annulus_nodes(section, row, theta)
        parent = np.tile(row, len(theta) - 1)
        mesh = mesh_from_points(x, groups=swept.pieces(section)[parent])
        counts = {"section": len(row), "theta": len(theta) - 1, "elements": mesh.nelements}
        return RefMesh(mesh, rep, counts, section, parent)
    x3 = None
    if rep == SOLID:
        extra = _breaks(case, rep)[2]
        x3 = (_span_nodes(0.0, ring_span(case, rep), extra, theta_step(case)) if case.body == RING
              else _span_nodes(0.0, case.length, extra, swept.median_size(section)))
    x = swept.element_nodes(case, section, x3)
    parent = swept.element_parents(section, x3)
    kept = ~_in_cutouts(case, rep, x[:, :, -1])
    # the section's pieces (the bodies of a scene of several) share no node: nor do their elements here
    pieces = swept.pieces(section)[parent]
    apart = swept.axis_tags(case, section, x3)  # where swept round the axis: its nodes there, tied
    mesh = mesh_from_points(x[:, kept], groups=pieces[kept], apart=None if apart is None else apart[kept])
    counts = {"section": len(section.elements), **({"x3": len(x3) - 1} if x3 is not None else {}),
              "elements": mesh.nelements}
    return RefMesh(mesh, rep, counts, section, parent[kept])


@dataclass(frozen=True)
class Grading:
    """Nodes graded toward the coordinates ``toward`` with exponent ``beta`` (1: uniform)."""

    toward: tuple = ()
    beta: float = 1.0

    def nodes(self, c0: float, c1: float, n: int) -> np.ndarray:
        """``n + 1`` nodes on ``[c0, c1]``, graded toward an end that is in ``toward``."""
        xi = np.linspace(0.0, 1.0, n + 1)
        tol = 1e-9 * max(abs(c0), abs(c1), c1 - c0)
        at0, at1 = (self.beta > 1 and any(abs(c - x) <= tol for x in self.toward) for c in (c0, c1))
        if at0 and at1:
            xi = np.where(xi <= 0.5, 0.5 * (2 * xi) ** self.beta, 1 - 0.5 * (2 * (1 - xi)) ** self.beta)
        elif at0:
            xi = xi**self.beta
        elif at1:
            xi = 1 - (1 - xi) ** self.beta
        return c0 + (c1 - c0) * xi


UNIFORM = Grading()


def axis_nodes(axis, scale: float, extra=(), grading: Grading = UNIFORM) -> np.ndarray:
    """Node coordinates along a section axis, shape ``(n + 1,)``.

    Each segment of ``axis`` keeps its element size divided by ``scale`` (refinable axes
    only); ``extra`` break points inside a segment split it, each part getting at least one
    element (graded as ``grading`` says).
    """
    scale = scale if axis.refinable else 1.0
    parts = []
    for a, b, n in zip(axis.breaks[:-1], axis.breaks[1:], axis.counts):
        h = (b - a) / max(1.0, n * scale)
        parts.append(_span_nodes(a, b, extra, h, grading)[:-1])
    return np.concatenate(parts + [np.array([axis.breaks[-1]])])


def _span_nodes(a: float, b: float, extra, h: float, grading: Grading = UNIFORM) -> np.ndarray:
    """Nodes on ``[a, b]`` with the breaks ``extra`` that fall inside, elements about ``h`` long
    (their count; the nodes graded as ``grading`` says)."""
    tol = 1e-9 * (b - a)
    cuts = sorted({a, b} | {float(e) for e in extra if a + tol < e < b - tol})
    parts = [grading.nodes(c0, c1, max(1, int(round((c1 - c0) / h))))[:-1] for c0, c1 in zip(cuts[:-1], cuts[1:])]
    return np.concatenate(parts + [np.array([b])])


def corner_lines(case) -> tuple[tuple, tuple, tuple]:
    """Coordinates ``(s, t, x3)`` of the cut-outs' limits that lie inside the body: the lines
    of their re-entrant corners (a limit on the body's boundary makes a convex corner)."""
    sec = case.section
    period = 2 * np.pi if case.body == RING else None
    inside = lambda v, lo, hi: lo + 1e-9 * (hi - lo) < v < hi - 1e-9 * (hi - lo)
    s, t, x3 = set(), set(), set()
    for c in case.cutouts:
        s |= {float(v) for v in c.s_range if inside(v, *sec.s.span)}
        t |= {float(v) for v in c.t_range if inside(v, *sec.t.span)}
        for a, b in c.x3_intervals:
            if period is not None:
                if not np.isclose(b - a, period):
                    x3 |= {float(np.mod(a, period)), float(np.mod(b, period))}
            else:
                x3 |= {float(v) for v in (a, b) if inside(v, 0.0, case.length)}
    return tuple(sorted(s)), tuple(sorted(t)), tuple(sorted(x3))


def _breaks(case, rep: str):
    """Break points along s, t and x3: cut-out, region and load limits, displacement-probe
    positions."""
    s_extra, t_extra, x3_extra = [], [], []
    for r in case.regions:
        if r.s_range is not None:
            s_extra += list(r.s_range)
            t_extra += list(r.t_range)
    for c in case.cutouts:
        s_extra += list(c.s_range)
        t_extra += list(c.t_range)
        x3_extra += [x for iv in c.x3_intervals for x in iv]
    for load in case.loads:
        x3_extra += [x for iv in load.x3_intervals for x in iv]
    for p in case.probes:
        if p.kind == "point" and p.field == "u":
            s, t = case.section.from_x(p.point[0], p.point[1])
            s_extra.append(float(s))
            t_extra.append(float(t))
            x3_extra.append(p.point[2])
    if case.body == RING:
        x3_extra = [float(np.mod(x, 2 * np.pi)) for x in x3_extra]
    return s_extra, t_extra, x3_extra


def _plane_blocks(case, s_nodes, t_nodes, x3_nodes):
    """The single block of a plane-strain mesh: ring annulus (s, theta) or prism (x3, t)."""
    sec = case.section
    dropped = sec.t if case.body == RING else sec.s
    if sec.kind != "rect" or dropped.refinable:
        why = " (a tilted wall is not axisymmetric)" if case.wall is not None and case.wall.slope else ""
        raise UnsupportedCase(f"reference solver: case {case.name!r} has no plane-strain 2D form{why}; use dim=3")
    if case.body == RING:
        def annulus(p):
            x1 = sec.to_x(p[0], 0.0)[0]
            return np.array([x1 * np.cos(p[1]), x1 * np.sin(p[1])])

        return [Block((s_nodes, x3_nodes), annulus)], {"s": len(s_nodes) - 1, "theta": len(x3_nodes) - 1}
    return [Block((x3_nodes, t_nodes), lambda p: np.array([p[0], sec.to_x(0.0, p[1])[1]]))], {
        "x3": len(x3_nodes) - 1, "t": len(t_nodes) - 1,
    }


def _axis_direction(section) -> str | None:
    """Which parametric direction starts on the axis r = 0 (``'s'`` or ``'t'``), if any."""
    (s0, s1), (t0, t1) = section.s.span, section.t.span
    size = max(abs(v) for v in (*section.to_x(s1, t1), *section.to_x(s0, t0), *section.to_x(s1, t0)))
    if np.all(np.abs(section.to_x(s0, np.linspace(t0, t1, 5))[0]) < 1e-12 * size):
        return "s"
    if np.all(np.abs(section.to_x(np.linspace(s0, s1, 5), t0)[0]) < 1e-12 * size):
        return "t"
    return None


def _ogrid_blocks(sec, s_nodes, t_nodes):
    """A solid of revolution around its axis: an O-grid disk swept along the other direction.

    The disk coordinates (X, Y), radius rho = |(X, Y)| <= 1, azimuth phi, map the
    axis-direction parameter linearly in rho; (x1, x2) = ``sec.to_x``; cartesian
    (x1 cos phi, x1 sin phi, x2). The map is smooth on the axis (x1 ~ rho).
    """
    along = _axis_direction(sec)
    radial_nodes, other = (s_nodes, t_nodes) if along == "s" else (t_nodes, s_nodes)
    lo, hi = radial_nodes[0], radial_nodes[-1]
    n = len(radial_nodes) - 1
    n_core = 2 * int(np.ceil(OGRID_CORE * n))
    n_ring = int(np.ceil((1 - OGRID_CORE) * n))
    c = OGRID_CORE

    def cap(disk, w):
        rho = np.hypot(disk[0], disk[1])
        u = lo + (hi - lo) * rho
        s, t = (u, w) if along == "s" else (w, u)
        x1, x2 = sec.to_x(s, t)
        safe = np.where(rho > 0, rho, 1.0)
        cos_phi, sin_phi = np.where(rho > 0, disk[0] / safe, 1.0), disk[1] / safe
        return np.array([x1 * cos_phi, x1 * sin_phi, x2])

    core = np.linspace(-c, c, n_core + 1)
    blocks = [Block((core, core, other), lambda p: cap(p[:2], p[2]))]
    for k in range(4):
        rot = np.array([[np.cos(k * np.pi / 2), -np.sin(k * np.pi / 2)], [np.sin(k * np.pi / 2), np.cos(k * np.pi / 2)]])

        def outer(p, rot=rot):
            lam, eta = p[0], p[1]
            square = np.array([np.full_like(eta, c), c * eta])
            circle = np.array([np.cos(np.pi / 4 * eta), np.sin(np.pi / 4 * eta)])
            return cap(rot @ ((1 - lam) * square + lam * circle), p[2])

        blocks.append(Block((np.linspace(0.0, 1.0, n_ring + 1), np.linspace(-1.0, 1.0, n_core + 1), other), outer))
    counts = {"core": n_core, "radial": n_ring, "around": 4 * n_core, "layers": len(other) - 1}
    return blocks, counts


def _in_cutouts(case, rep: str, x: np.ndarray) -> np.ndarray:
    """Mask of mesh points (element centres) ``x``, shape ``(dim, n)``, inside a cut-out."""
    if not case.cutouts:
        return np.zeros(x.shape[1], bool)
    s, t = section_of(case, rep, x)
    x3 = x3_of(case, rep, x)
    period = 2 * np.pi if case.body == RING else None
    mask = np.zeros(x.shape[1], bool)
    for c in case.cutouts:
        inside = np.ones(x.shape[1], bool)
        axes = (case.section.s, case.section.t) if case.section.kind != "mesh" else (None, None)
        for v, (a, b), axis in ((s, c.s_range, axes[0]), (t, c.t_range, axes[1])):
            if np.all(np.isnan(v)):
                # a dropped (plane-strain) direction: the cut-out must run through all of it
                if not np.allclose((a, b), axis.span):
                    raise UnsupportedCase("reference solver: a cut-out that does not span the plane-strain "
                                     "direction needs dim=3")
                continue
            inside &= (v > a) & (v < b)
        if rep == AXISYMMETRIC:
            if not np.allclose(sum(b - a for a, b in c.x3_intervals), 2 * np.pi):
                raise UnsupportedCase("reference solver: a cut-out that is not axisymmetric needs dim=3")
        else:
            inside &= in_intervals(x3, c.x3_intervals, period)
        mask |= inside
    return mask


def assemble_blocks(blocks, keep: Callable[[np.ndarray], np.ndarray]) -> MeshQuad2 | MeshHex2:
    """Quadratic mesh from structured blocks; ``keep(centres)`` selects the elements.

    Parameters
    ----------
    blocks : list of :class:`Block`, all with 2 or all with 3 parametric directions
    keep : maps element centres, shape ``(dim, n_elements)``, to a boolean mask

    Nodes shared by blocks (or across a periodic seam) are merged by position.
    """
    pdim = len(blocks[0].axes)
    ref = (ElementQuad2 if pdim == 2 else ElementHex2).doflocs  # (n_local_nodes, pdim); vertices first, centre last
    xs = []
    for block in blocks:
        idx = np.meshgrid(*(np.arange(len(a) - 1) for a in block.axes), indexing="ij")
        lo = np.array([a[i.ravel()] for a, i in zip(block.axes, idx)])
        hi = np.array([a[i.ravel() + 1] for a, i in zip(block.axes, idx)])
        param = lo[:, :, None] + (hi - lo)[:, :, None] * ref.T[:, None, :]
        x = block.to_mesh(param.reshape(pdim, -1))
        xs.append(x.reshape(x.shape[0], lo.shape[1], ref.shape[0]))
    return mesh_from_points(np.concatenate(xs, axis=1), keep)


def mesh_from_points(x: np.ndarray, keep: Callable[[np.ndarray], np.ndarray] | None = None,
                     groups: np.ndarray | None = None, apart: np.ndarray | None = None) -> MeshQuad2 | MeshHex2:
    """Quadratic mesh of elements given by their nodes ``x`` (dim, n_elements, 9 | 27) in the
    order of scikit-fem's reference element (``ElementQuad2`` / ``ElementHex2.doflocs``);
    ``keep(centres)`` selects the elements (None: all), in their order. Coincident nodes are
    merged by position, within one of ``groups`` (n_elements,) only when given: two bodies
    that touch keep a row of nodes each. ``apart`` (n_elements, 27): tags of the nodes that
    coincident vertices of different tags keep apart in the mesh and tie as unknowns (a 3D
    mesh's nodes on the axis, one per angle: :class:`MeshHex2Tied`, :mod:`reference_fem.ties`)."""
    pdim = x.shape[0]
    elem, lin_cls, quad_cls = (ElementQuad2, MeshQuad1, MeshQuad2Curved) if pdim == 2 else (ElementHex2, MeshHex1, MeshHex2Curved)
    ref = elem.doflocs
    if keep is not None:
        kept = keep(x[:, :, -1])
        x, groups = x[:, kept], None if groups is None else np.asarray(groups)[kept]
        apart = None if apart is None else apart[kept]
    x, flipped = _positively_oriented(x, ref)
    n_vert = elem.refdom.nnodes
    scale = np.abs(x).max()
    keys = [] if groups is None else [np.repeat(np.asarray(groups, np.int64), n_vert)]
    if apart is not None:
        apart = np.where(flipped[:, None], apart[:, mirror_permutation(ref)], apart)
        keys.append(np.asarray(apart, np.int64)[:, :n_vert].ravel())
    vid, p = _merge(x[:, :, :n_vert].reshape(x.shape[0], -1), scale, np.array(keys) if keys else None)
    lin = lin_cls(np.ascontiguousarray(p), np.ascontiguousarray(vid.reshape(-1, n_vert).T))
    mesh = (MeshHex2Tied if apart is not None else quad_cls).from_mesh(lin)
    doflocs = mesh.doflocs.copy()
    doflocs[:, mesh.dofs.element_dofs] = x.transpose(0, 2, 1)
    if apart is None:
        return replace(mesh, doflocs=doflocs)
    return replace(mesh, doflocs=doflocs, ties=ties.tie_coincident(doflocs, mesh.dofs.element_dofs, groups, scale))


def _merge(points: np.ndarray, scale: float, group: np.ndarray | None = None):
    """Ids of coincident points (within 1e-9 ``scale``; of one ``group`` (k, n) of integer keys
    when given) and the unique points, ``(dim, m)``."""
    key = np.round(points / (1e-9 * scale)).astype(np.int64)
    if group is not None:
        key = np.vstack([key, np.atleast_2d(group)])
    _, first, inverse = np.unique(key.T, axis=0, return_index=True, return_inverse=True)
    return inverse.ravel(), points[:, first]


def vtk_cells(mesh: MeshQuad2 | MeshHex2) -> tuple[str, np.ndarray]:
    """The elements as VTK cells, ``('quad9' | 'hexahedron27', (n_elements, 9 | 27))`` node
    indices (of :func:`reference_fem.ties.node_positions`: a node tied on the axis once); their
    first 8 or 20 nodes are also Abaqus's CPE8/CAX8 or C3D20 in its order."""
    cells = ties.cells(mesh)
    if mesh.dim() == 2:
        return "quad9", cells.T
    # scikit-fem's reference hexahedron is left-handed in VTK's node order: mirror it
    return "hexahedron27", cells[mirror_permutation(ElementHex2.doflocs)][HEX_MAPPING].T


def mirror_permutation(ref: np.ndarray) -> list[int]:
    """Local node permutation of the reflection xi_1 -> 1 - xi_1 of reference nodes ``ref``."""
    mirrored = ref.copy()
    mirrored[:, 0] = 1 - mirrored[:, 0]
    return [int(np.argmin(np.abs(ref - m).sum(axis=1))) for m in mirrored]


def _positively_oriented(x: np.ndarray, ref: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Reorder the local nodes of elements whose map reverses orientation (mirror in xi_1);
    also which were. The orientation is the map's at the element's centre, whose derivative
    along each reference direction is the difference of the two nodes on that line through the
    centre (the quadratic functions' slopes there are -1, 0, 1): a hexahedron degenerate on the
    axis has an edge of zero length at its corners, not there."""
    pdim = ref.shape[1]
    centre = np.full(pdim, 0.5)
    ends = [[int(np.argmin(np.abs(ref - np.where(np.arange(pdim) == d, side, centre)).sum(axis=1))) for side in (0.0, 1.0)]
            for d in range(pdim)]
    edges = np.stack([x[:, :, hi] - x[:, :, lo] for lo, hi in ends], axis=-1)
    det = np.linalg.det(edges.transpose(1, 0, 2))
    out = x.copy()
    out[:, det < 0] = x[:, det < 0][:, :, mirror_permutation(ref)]
    return out, det < 0
