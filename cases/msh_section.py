"""A body's cross-section read from a gmsh mesh (``.msh``, MSH 2.2 or 4.1, through meshio).

The section is a quadrilateral mesh in section coordinates (ring: ``x1 = r``, ``x2 = z``; prism:
``x1``, ``x2``; :mod:`cases.geometry` defines them), drawn in gmsh's x-y plane (x -> x1,
y -> x2). Every element is kept as 9-node geometry, so that a curved boundary meshed with quad9
stays curved under :meth:`MeshSection.refined`, and a quad4 mesh is its bilinear special case.
gmsh's physical curves become named edges (loads, supports), its physical surfaces named
regions (materials).

:func:`read_msh` refuses, with one line naming the file, what is wrong, where and what to do,
every mesh a solver could not use as it is: triangles, incomplete quadrilaterals, mixed orders,
a third coordinate, degenerate or inverted elements, cracks and hanging nodes, lines that are
not element edges, overlapping or empty groups. Clockwise elements are reordered silently.

A mesh may hold several bodies: connected pieces that share no node (:attr:`MeshSection.pieces`),
each its own physical surface. Two such bodies may touch, a row of nodes of each at the same
places (:attr:`MeshSection.touching`; a contact pair joins them, :mod:`cases.bodies`); two nodes
at one point within one piece, or in two pieces of one physical surface, are a crack.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import ClassVar

import meshio
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from cases.params import UnsupportedCase, failure, one_line

#: the body names of :mod:`cases.geometry` (its RING and PRISM)
BODIES = ("ring", "prism")
#: two nodes closer than this (times the section size) are one point
COINCIDENT = 1e-9
#: a point this far (times the section size) outside the section is outside; a node this close
#: to an element edge's interior hangs on it
OUTSIDE = 1e-6
#: a point this close (times the section size) to an element's image is in it
EXACT = 1e-12
#: reference coordinates of the 9 nodes: corners counter-clockwise, mid-sides of edges 0-1,
#: 1-2, 2-3, 3-0, centre (gmsh's and VTK's quad9 order)
NODE_XI = np.array([-1.0, 1.0, 1.0, -1.0, 0.0, 1.0, 0.0, -1.0, 0.0])
NODE_ETA = np.array([-1.0, -1.0, 1.0, 1.0, -1.0, 0.0, 1.0, 0.0, 0.0])
#: the corners of local edge l (its mid-side node is node 4 + l)
EDGE_CORNERS = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
#: node order of the mirror image: a clockwise element made counter-clockwise
MIRROR = np.array([0, 3, 2, 1, 7, 6, 5, 4, 8])
#: what to do about a mesh whose elements do not share their edges' nodes
CONFORM = "make the mesh conforming (one mesh for the section, gmsh: Coherence)"
MERGE = "merge duplicate nodes (gmsh: Coherence / Geometry.Tolerance)"
#: 3-point Gauss-Legendre rule on [-1, 1] (an element's area, exactly)
GAUSS_1D, WEIGHTS_1D = np.polynomial.legendre.leggauss(3)
#: candidate elements tried per point by :meth:`MeshSection.locate`, nearest corner polygon first
LOCATE_TRIES = 8
#: the 9 nodes on the 3 x 3 lattice of reference positions, [i, j] along (xi, eta)
LATTICE = np.zeros((3, 3), np.int64)
LATTICE[(NODE_XI + 1).astype(int), (NODE_ETA + 1).astype(int)] = np.arange(9)
#: a quadratic's values at -1, 0, 1 -> its Bezier control points (the curve lies in their hull)
TO_BEZIER = np.array([[1.0, 0.0, 0.0], [-0.5, 2.0, -0.5], [0.0, 0.0, 1.0]])

QUADS, CURVES = ("quad", "quad9"), ("line", "line3")
GMSH_QUADS = "gmsh: Mesh.RecombineAll = 1, Mesh.Algorithm = 8 or 11"
REFUSED = {
    "triangle": ("triangles", f"make quadrilaterals ({GMSH_QUADS})"),
    "triangle6": ("6-node triangles",
                  f"make quadrilaterals ({GMSH_QUADS}, Mesh.SecondOrderIncomplete = 0)"),
    "quad8": ("8-node quadrilaterals (quad8)",
              "make 9-node ones (gmsh: Mesh.SecondOrderIncomplete = 0)"),
}


class SectionImportError(UnsupportedCase):
    """A section mesh that cannot be used as it is, or a point outside it: one line naming the
    file, what is wrong, where, and what to do."""


def lagrange(s):
    """Quadratic Lagrange functions at -1, 0, 1 and their derivatives: two ``(..., 3)``."""
    s = np.asarray(s, float)[..., None]
    return (np.concatenate([s * (s - 1) / 2, 1 - s * s, s * (s + 1) / 2], axis=-1),
            np.concatenate([s - 0.5, -2 * s, s + 0.5], axis=-1))


def shape(xi, eta):
    """Biquadratic ``N``, ``dN/dxi``, ``dN/deta`` at reference points in [-1, 1]^2: three
    ``(..., 9)``."""
    (a, da), (b, db) = lagrange(xi), lagrange(eta)
    i, j = (NODE_XI + 1).astype(int), (NODE_ETA + 1).astype(int)
    return a[..., i] * b[..., j], da[..., i] * b[..., j], a[..., i] * db[..., j]


def jacobian(X, xi, eta) -> np.ndarray:
    """det J of elements ``X (n_el, 9, 2)`` at reference points ``xi, eta (p,)``: ``(n_el, p)``."""
    _, dxi, deta = shape(xi, eta)
    a, b = np.einsum("pn,enc->epc", dxi, X), np.einsum("pn,enc->epc", deta, X)
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _size(x) -> float:
    """The section's size (its bounding box diagonal), the scale of every tolerance."""
    return float(np.hypot(*np.ptp(x, axis=0))) or 1.0


def _at(p) -> str:
    """A point for a message: ``(x1, x2)``."""
    return "(" + ", ".join(f"{v:.6g}" for v in p) + ")"


@dataclass(frozen=True, eq=False)
class MeshSection:
    """A cross-section given as a quadrilateral mesh (x1, x2 section coordinates: ring x1 = r,
    x2 = z).

    Attributes
    ----------
    x : (n_nodes, 2) float
        Node positions.
    elements : (n_el, 9) int
        Always 9-node geometry: corners counter-clockwise (positive area in (x1, x2)), then the
        mid-sides of edges 0-1, 1-2, 2-3, 3-0, then the centre. A quad4 mesh has straight
        mid-sides and the centre of its bilinear map.
    source_order : int
        1 if the file had quad4 elements, 2 if quad9.
    edges : dict[str, (n_seg, 3) int]
        Physical curve name -> node ids ``[a, mid, b]`` of each element edge on it, running
        counter-clockwise round its owner (the owner's outward normal is to the right of a -> b),
        in chains along the curve where segments join.
    edge_owner : dict[str, (n_seg,) int]
        Name -> the element owning each segment (on an interior curve, the lower element id).
    regions : dict[str, (n,) int]
        Physical surface name -> sorted element ids; one region ``"body"`` if the file has no
        physical surfaces.
    path : str
        Where the mesh came from, for messages.

    Equal sections have equal nodes, elements, edges and regions (``path`` aside); the arrays
    are shared with derived objects and are not to be written.
    """

    x: np.ndarray
    elements: np.ndarray
    source_order: int
    edges: dict[str, np.ndarray]
    edge_owner: dict[str, np.ndarray]
    regions: dict[str, np.ndarray]
    path: str = field(default="", compare=False)

    kind: ClassVar[str] = "mesh"

    def __post_init__(self):
        # one dtype each, so that equal sections hash alike
        object.__setattr__(self, "x", np.asarray(self.x, float))
        object.__setattr__(self, "elements", np.asarray(self.elements, np.int64))

    def __eq__(self, other):
        if not isinstance(other, MeshSection):
            return NotImplemented

        def same(a, b):
            return a.keys() == b.keys() and all(np.array_equal(a[n], b[n]) for n in a)

        return (self.source_order == other.source_order and np.array_equal(self.x, other.x)
                and np.array_equal(self.elements, other.elements) and same(self.edges, other.edges)
                and same(self.edge_owner, other.edge_owner) and same(self.regions, other.regions))

    def __hash__(self):
        return hash((self.source_order, self.elements.shape, self.elements.tobytes()))

    def mesh(self, scale: float = 1, extra=((), ()), order: int = 1):
        """The section protocol (:mod:`cases.section_mesh`): this mesh split ``scale`` x ``scale``."""
        from .section_mesh import unstructured_mesh

        return unstructured_mesh(self, scale, extra, order)

    def inside(self, n: int = 7):
        """The section protocol: ``(x1, x2)`` of about n x n points inside the section (the
        centres of elements spread over it), flat arrays."""
        centres = self.x[self.elements[:: max(1, len(self.elements) // (n * n)), 8]]
        return centres[:, 0], centres[:, 1]

    def contains(self, x1: float, x2: float) -> bool:
        """The section protocol: whether section point ``(x1, x2)`` lies in the section (to round-off)."""
        try:
            self.locate(np.array([x1], float), np.array([x2], float))
        except ValueError:
            return False
        return True

    @property
    def smallest_dimension(self) -> float:
        """The smaller extent of the section's bounding box."""
        (a, b), (c, d) = self.bounds
        return min(b - a, d - c)

    @staticmethod
    def to_x(s, t):
        """A mesh section's parametric coordinates are its section coordinates."""
        return np.asarray(s, float), np.asarray(t, float)

    from_x = to_x

    def edge(self, name: str) -> str:
        """The physical curve ``name`` (edges are named by the mesh, not by parametric sides)."""
        return name

    def digest(self) -> str:
        """sha256 (16 hex digits) of the nodes, elements, edges and regions: what a stored
        truth's key holds of the section (an array's text is cut short by numpy)."""
        import hashlib

        h = hashlib.sha256()
        for a in (self.x, self.elements):
            h.update(np.ascontiguousarray(a).tobytes())
        for table in (self.edges, self.edge_owner, self.regions):
            for name in sorted(table):
                h.update(name.encode())
                h.update(np.ascontiguousarray(table[name], np.int64).tobytes())
        return h.hexdigest()[:16]

    @property
    def bounds(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """``((x1min, x1max), (x2min, x2max))`` of the nodes."""
        lo, hi = self.x.min(axis=0), self.x.max(axis=0)
        return (float(lo[0]), float(hi[0])), (float(lo[1]), float(hi[1]))

    def refined(self, k: int) -> MeshSection:
        """Every element split ``k x k`` through its 9-node map, so that new nodes on a curved
        edge lie on the quadratic edge curve (and the refined map is the same map: the area does
        not change). Nodes on an element edge are shared by construction: they are placed along
        the edge from its lower corner id, whichever element they are made for. Each segment of
        an edge becomes ``k`` segments (in order along it), each region ``k^2`` times as many
        elements (element ``e`` becomes ``e k^2 .. e k^2 + k^2 - 1``). ``k = 1`` returns self.
        """
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
            raise ValueError(f"refined: k must be an integer >= 1, not {k!r}")
        if k == 1:
            return self
        m, n_el, el = 2 * k, len(self.elements), self.elements
        s = np.linspace(-1.0, 1.0, m + 1)  # the lattice of the sub-elements' nodes, per direction
        # element edges: the mid-side node names one (it is shared by the elements sharing it)
        edge_mid, first, edge_of = np.unique(el[:, 4:8], return_index=True, return_inverse=True)
        edge_of = edge_of.reshape(n_el, 4)
        ends_a, ends_b = el[:, EDGE_CORNERS[:, 0]], el[:, EDGE_CORNERS[:, 1]]
        lo = np.minimum(ends_a, ends_b).ravel()[first]
        hi = np.maximum(ends_a, ends_b).ravel()[first]
        inner = np.r_[1:k, k + 1:m]  # lattice points inside an edge, the mid-side aside
        three = np.stack([self.x[lo], self.x[edge_mid], self.x[hi]], axis=1)  # (n_edge, 3, 2)
        along = lagrange(s[inner])[0] @ three
        n, n_edge = len(self.x), len(edge_mid)
        edge_ids = np.empty((n_edge, m + 1), np.int64)
        edge_ids[:, 0], edge_ids[:, k], edge_ids[:, m] = lo, edge_mid, hi
        edge_ids[:, inner] = n + np.arange(n_edge * (m - 2)).reshape(n_edge, m - 2)
        # each element's (m + 1) x (m + 1) lattice of node ids, [i, j] along (xi, eta)
        lattice = np.empty((n_el, m + 1, m + 1), np.int64)
        path_i, path_j = _edge_paths(m)
        for l in range(4):
            ids = edge_ids[edge_of[:, l]]
            forward = (ends_a[:, l] < ends_b[:, l])[:, None]
            lattice[:, path_i[l], path_j[l]] = np.where(forward, ids, ids[:, ::-1])
        ii, jj = (a.ravel() for a in np.meshgrid(np.arange(1, m), np.arange(1, m), indexing="ij"))
        keep = (ii != k) | (jj != k)
        ii, jj = ii[keep], jj[keep]
        first_inside = n + n_edge * (m - 2)
        lattice[:, ii, jj] = first_inside + np.arange(n_el * len(ii)).reshape(n_el, len(ii))
        lattice[:, k, k] = el[:, 8]
        inside = np.einsum("pn,enc->epc", shape(s[ii], s[jj])[0], self.x[el]).reshape(-1, 2)
        x = np.concatenate([self.x, along.reshape(-1, 2), inside])
        sub_i, sub_j, sub_of_edge = _sub_elements(k)
        elements = lattice[:, sub_i, sub_j].reshape(-1, 9)
        edges, owners = {}, {}
        for name, seg in self.edges.items():
            owner = self.edge_owner[name]
            l = np.argmax(el[owner, 4:8] == seg[:, 1:2], axis=1)
            ids = lattice[owner[:, None], path_i[l], path_j[l]]  # (n_seg, m + 1), local direction
            subs = owner[:, None] * k * k + sub_of_edge[l]  # (n_seg, k)
            flip = seg[:, 0] != el[owner, l]
            ids[flip], subs[flip] = ids[flip, ::-1], subs[flip, ::-1]
            edges[name] = np.stack([ids[:, 0:m:2], ids[:, 1:m:2], ids[:, 2::2]], axis=-1).reshape(-1, 3)
            owners[name] = subs.ravel()
        regions = {name: (ids[:, None] * k * k + np.arange(k * k)).ravel()
                   for name, ids in self.regions.items()}
        return MeshSection(x, elements, self.source_order, edges, owners, regions, self.path)

    def at_order(self, order: int) -> tuple[np.ndarray, np.ndarray, dict]:
        """The mesh as a solver of ``order`` 1 or 2 takes it: ``(x, elements, edges)``.

        Order 2: ``x (n, 2)``, ``elements (n_el, 9)``, ``{name: (segments (n_seg, 3) [a, mid, b],
        owners (n_seg,))}``. Order 1: the corner nodes only, numbered compactly in the order of
        their ids here, ``elements (n_el, 4)``, segments ``(n_seg, 2) [a, b]``.
        """
        if order == 2:
            return self.x, self.elements, {n: (self.edges[n], self.edge_owner[n]) for n in self.edges}
        if order != 1:
            raise ValueError(f"at_order: order must be 1 or 2, not {order!r}")
        corners = self.elements[:, :4]
        used = np.unique(corners)
        new = np.full(len(self.x), -1, np.int64)
        new[used] = np.arange(len(used))
        return (self.x[used], new[corners],
                {n: (new[seg[:, [0, 2]]], self.edge_owner[n]) for n, seg in self.edges.items()})

    def locate(self, x1, x2) -> tuple[np.ndarray, np.ndarray]:
        """The element and reference coordinates ``(xi, eta)`` in [-1, 1]^2 of section points.

        Newton's method on the 9-node map in the elements whose boxes hold the point (found
        through a uniform grid), nearest corner polygon first (containing the point: distance
        zero), up to 8 of them: the first whose map reaches the point, else the one whose map
        comes closest, its reference coordinates clipped to [-1, 1]^2, so that a point a
        round-off outside lands on the boundary.

        Parameters
        ----------
        x1, x2 : array_like
            Coordinates, broadcast together and flattened to ``n`` points.

        Returns
        -------
        element : (n,) int
        ref : (n, 2) float

        Raises
        ------
        SectionImportError
            (a ValueError) for a point farther than 1e-6 of the section's size outside it.
        """
        x1, x2 = np.broadcast_arrays(np.asarray(x1, float), np.asarray(x2, float))
        p = np.column_stack([x1.ravel(), x2.ravel()])
        X = self.x[self.elements]
        size = _size(self.x)
        tries = min(LOCATE_TRIES, len(X))
        element, ref = np.empty(len(p), np.int64), np.empty((len(p), 2))
        for start in range(0, len(p), 10_000):
            q = p[start:start + 10_000]
            rows = np.arange(len(q))
            point, near = _pairs(self._buckets, q)
            lost = np.setdiff1d(rows, point)
            if len(lost):  # in no element's box
                gap = _polygon_gap(X[:, :4], np.broadcast_to(q[lost[0]], (len(X), 2))).min()
                raise self._outside(q[lost[0]], gap)
            # per point: nearest corner polygon first, then the lower element id
            order = np.lexsort((near, _polygon_gap(X[near, :4], q[point]), point))
            point, near = point[order], near[order]
            first = np.searchsorted(point, rows)
            rank = np.arange(len(point)) - first[point]
            candidates = np.repeat(near[first][:, None], tries, axis=1)  # padded with the nearest
            candidates[point[rank < tries], rank[rank < tries]] = near[rank < tries]
            # the nearest element first; the others only for points it does not hold exactly
            xi, miss = np.zeros((len(q), tries, 2)), np.full((len(q), tries), np.inf)
            xi[:, 0], miss[:, 0] = _inverse(X[candidates[:, 0]], q)
            rest = np.flatnonzero(miss[:, 0] > EXACT * size)
            xi[rest, 1:], miss[rest, 1:] = _inverse(X[candidates[rest, 1:]], q[rest, None, :])
            best = np.argmin(miss, axis=1)
            outside = np.flatnonzero(miss[rows, best] > OUTSIDE * size)
            if len(outside):
                raise self._outside(q[outside[0]], miss[outside[0], best[outside[0]]])
            element[start:start + len(q)] = candidates[rows, best]
            ref[start:start + len(q)] = xi[rows, best]
        return element, ref

    def _outside(self, point, gap) -> SectionImportError:
        """The error for ``point``, ``gap`` outside the section."""
        return SectionImportError(one_line(
            f"{self.path or 'section'}: point (x1, x2) = {_at(point)} lies outside the section "
            f"(by about {gap:.3g}): move it inside"))

    @cached_property
    def pieces(self) -> np.ndarray:
        """The connected piece each element is in, ``(n_el,)`` int: elements sharing a node are
        of one piece (the bodies of a section of several share none)."""
        return _pieces(self.elements, len(self.x))

    @cached_property
    def touching(self) -> np.ndarray:
        """Where bodies touch: the pairs of nodes at one point (within round-off) in different
        pieces, ``(n, 2)`` int, the lower id first."""
        pairs = _coincident(self.x, COINCIDENT * _size(self.x))
        piece = _node_labels(self.elements, self.pieces, len(self.x))
        return pairs[piece[pairs[:, 0]] != piece[pairs[:, 1]]]

    @cached_property
    def _buckets(self):
        """The elements by the cells of a uniform grid that their boxes overlap (:func:`_pairs`),
        made on the first :meth:`locate`."""
        return _buckets(self.x[self.elements], OUTSIDE * _size(self.x))


def _edge_paths(m: int) -> tuple[np.ndarray, np.ndarray]:
    """Lattice indices ``(i, j)`` along each local edge, from its first corner to its second:
    two ``(4, m + 1)``."""
    t, end = np.arange(m + 1), np.full(m + 1, m)
    zero = np.zeros(m + 1, int)
    return np.stack([t, end, m - t, zero]), np.stack([zero, t, end, m - t])


def _sub_elements(k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For an element split ``k x k`` (sub-element ``q k + p`` is the p-th along xi, q-th along
    eta): each sub-element's 9 lattice indices ``(i, j)``, two ``(k^2, 9)``, and the sub-elements
    along each local edge in its direction, ``(4, k)``."""
    p, q = (a.ravel() for a in np.meshgrid(np.arange(k), np.arange(k), indexing="xy"))
    sub_i = 2 * p[:, None] + (NODE_XI + 1).astype(int)
    sub_j = 2 * q[:, None] + (NODE_ETA + 1).astype(int)
    t = np.arange(k)
    along = np.stack([t, t * k + k - 1, (k - 1) * k + k - 1 - t, (k - 1 - t) * k])
    return sub_i, sub_j, along


def _buckets(X, margin):
    """A uniform grid of about one cell per element over the elements ``X (n_el, 9, 2)``, and
    the elements whose boxes (of their Bezier control points, which hold the curved element,
    widened by ``margin``) overlap each cell: ``(origin, h, (nx, ny), start, members)``, the
    members of cell ``ix ny + iy`` being ``members[start[c]:start[c + 1]]``."""
    net = X[:, LATTICE]  # (n_el, 3, 3, 2), [i, j] along (xi, eta)
    control = np.einsum("ai,bj,eijc->eabc", TO_BEZIER, TO_BEZIER, net).reshape(len(X), 9, 2)
    lo, hi = control.min(axis=1) - margin, control.max(axis=1) + margin
    origin, extent = lo.min(axis=0), hi.max(axis=0) - lo.min(axis=0)
    h = max(math.sqrt(extent[0] * extent[1] / len(X)), extent.max() / len(X))
    n = (extent // h).astype(np.int64) + 1
    i0 = np.clip(((lo - origin) // h).astype(np.int64), 0, n - 1)
    i1 = np.clip(((hi - origin) // h).astype(np.int64), 0, n - 1)
    span = i1 - i0 + 1  # (n_el, 2) cells along x and y
    count = span[:, 0] * span[:, 1]
    owner = np.repeat(np.arange(len(X)), count)
    local = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
    cell = (i0[owner, 0] + local % span[owner, 0]) * n[1] + i0[owner, 1] + local // span[owner, 0]
    order = np.argsort(cell, kind="stable")
    start = np.searchsorted(cell[order], np.arange(n[0] * n[1] + 1))
    return origin, h, n, start, owner[order]


def _pairs(buckets, q) -> tuple[np.ndarray, np.ndarray]:
    """``(point, element)`` index pairs: each point of ``q (nq, 2)`` with every element whose box
    holds its grid cell."""
    origin, h, n, start, members = buckets
    ix = ((q - origin) // h).astype(np.int64)
    inside = np.flatnonzero(np.all((ix >= 0) & (ix < n), axis=1))
    cell = ix[inside, 0] * n[1] + ix[inside, 1]
    count = start[cell + 1] - start[cell]
    point = np.repeat(inside, count)
    offset = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)  # within a cell
    return point, members[np.repeat(start[cell], count) + offset]


def _polygon_gap(corners, q) -> np.ndarray:
    """Distance of each point ``q (n, 2)`` from its corner polygon ``(n, 4, 2)`` (counter-
    clockwise), zero inside: ``(n,)``."""
    d = np.roll(corners, -1, axis=1) - corners  # the sides, (n, 4, 2)
    w = q[:, None, :] - corners
    inside = np.all(d[..., 0] * w[..., 1] - d[..., 1] * w[..., 0] >= 0, axis=-1)
    length2 = np.maximum(np.einsum("nlc,nlc->nl", d, d), 1e-300)
    t = np.clip(np.einsum("nlc,nlc->nl", w, d) / length2, 0, 1)  # nearest point on each side
    gap = np.linalg.norm(w - t[..., None] * d, axis=-1).min(axis=-1)
    return np.where(inside, 0.0, gap)


def _inverse(X, q) -> tuple[np.ndarray, np.ndarray]:
    """Reference coordinates in [-1, 1]^2 of ``q (..., 2)`` in the elements ``X (..., 9, 2)``,
    and how far their image is from ``q`` (zero inside): ``(..., 2)``, ``(...)``."""
    xi = np.clip(_newton(X, q), -1.0, 1.0)
    image = np.einsum("...n,...nc->...c", shape(xi[..., 0], xi[..., 1])[0], X)
    miss = np.linalg.norm(image - q, axis=-1)
    return xi, np.where(np.isfinite(miss), miss, np.inf)


def _newton(X, q, steps: int = 20) -> np.ndarray:
    """Reference coordinates ``(..., 2)`` where the 9-node maps of ``X (..., 9, 2)`` reach
    ``q (..., 2)``, by Newton's method from the centre (kept within [-3, 3]^2: a point outside
    an element may have no solution)."""
    xi = np.zeros(X.shape[:-2] + (2,))
    for _ in range(steps):
        N, dxi, deta = shape(xi[..., 0], xi[..., 1])
        r = q - np.einsum("...n,...nc->...c", N, X)
        a, b = np.einsum("...n,...nc->...c", dxi, X), np.einsum("...n,...nc->...c", deta, X)
        det = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
        det = np.where(np.abs(det) > 1e-300, det, np.inf)  # singular: stay
        step = np.stack([b[..., 1] * r[..., 0] - b[..., 0] * r[..., 1],
                         a[..., 0] * r[..., 1] - a[..., 1] * r[..., 0]], axis=-1) / det[..., None]
        xi = np.clip(xi + step, -3.0, 3.0)
        if not np.any(np.abs(step) > 1e-15):  # converged (NaN steps stop nothing)
            break
    return xi


def read_msh(path, body: str = "ring") -> MeshSection:
    """Read and check the section mesh in the gmsh file ``path``.

    Parameters
    ----------
    path : str or Path
        An ``.msh`` file (MSH 2.2 or 4.1, ASCII or binary) of quad or quad9 elements in the x-y
        plane, with named physical curves (edges) and surfaces (regions).
    body : {"ring", "prism"}
        A ring section must lie in r = x1 >= 0 (nodes within round-off of the axis are put on it).

    Returns
    -------
    MeshSection
        Its elements in the order of the file's quadrilaterals (messages name them so), its
        nodes those of the quadrilaterals, in file order, then (quad4) the mid-sides and centres.

    Raises
    ------
    SectionImportError
        With one line for every mesh a solver cannot use (module docstring).
    """
    if body not in BODIES:
        raise ValueError(f"read_msh: body must be one of {BODIES}, not {body!r}")
    where = str(path)

    def refuse(text):
        return SectionImportError(one_line(f"{where}: {text}"))

    mesh = _read(path, refuse)
    quads, lines, groups = _cells(mesh, refuse)
    points = np.asarray(mesh.points, float)
    used = np.unique(quads)
    size = _size(points[used, :2])
    if points.shape[1] > 2:
        off = np.flatnonzero(np.abs(points[used, 2]) > COINCIDENT * size)
        if len(off):
            raise refuse(f"node at (x, y, z) = {_at(points[used[off[0]]])} is off the x-y plane: "
                         "draw the section at z = 0 (x -> x1, y -> x2)")
    # nodes in no quadrilateral are dropped
    new = np.full(len(points), -1, np.int64)
    new[used] = np.arange(len(used))
    x, quads = points[used, :2].copy(), new[quads]
    lines = np.where(lines >= 0, new[lines], -1)
    if body == "ring":
        below = np.flatnonzero(x[:, 0] < -COINCIDENT * size)
        if len(below):
            raise refuse(f"reaches r < 0 at node (x1, x2) = {_at(x[below[0]])}: a ring section lies in "
                         "r = x >= 0: move it to the right of the axis")
        x[:, 0] = np.maximum(x[:, 0], 0.0)
    source_order = 1 if quads.shape[1] == 4 else 2
    n_file = len(x)
    if source_order == 1:
        x, elements = _quadratic(x, quads)
    else:
        elements = quads
    elements = _counter_clockwise(x, elements, refuse)
    regions = _regions(x, elements, groups, refuse)  # first: it names duplicated elements' groups
    _check_nodes(x, elements, refuse)
    pieces = _pieces(elements, len(x))
    _check_hanging(x, elements, pieces, size, refuse)
    _check_coincident(x, n_file, elements, pieces, regions, size, refuse)
    edges, owners = _edges(x, elements, lines, groups, refuse)
    return MeshSection(x, elements, source_order, edges, owners, regions, where)


def _read(path, refuse) -> meshio.Mesh:
    """The file as meshio's gmsh reader gives it (``meshio.read`` would try ANSYS first on a
    ``.msh``, print its failure and exit the process on a file neither reads)."""
    if not Path(path).is_file():
        raise refuse("no such file: check the path")
    try:
        return meshio.gmsh.read(str(path))
    except Exception as exc:  # noqa: BLE001 - malformed input fails anywhere in the reader
        raise refuse(f"cannot be read as a gmsh mesh ({failure(exc)}): save it from gmsh as MSH 2.2 "
                     "or 4.1 with physical groups (Mesh.SaveAll = 0)") from None


def _cells(mesh, refuse):
    """The quadrilaterals ``(n_quad, 4 | 9)``, the lines ``(n_line, 3)`` ``[a, b, mid]`` (mid -1
    for 2-node lines) and the physical groups ``(name, dim, kind, ids)``: ``kind`` "quad" or
    "line", ``ids`` indices into the quadrilaterals or the lines."""
    counts = Counter()
    for block in mesh.cells:
        counts[block.type] += len(block.data)
    for kind, n in counts.items():
        if kind in REFUSED:
            what, todo = REFUSED[kind]
            raise refuse(f"has {n} {what}: {todo}")
        if kind not in QUADS + CURVES + ("vertex",):
            raise refuse(f"has {n} {kind} cells: a section is quadrilaterals (quad or quad9) in the "
                         "x-y plane with line edges")
    orders = [kind for kind in QUADS if counts[kind]]
    if not orders:
        raise refuse("has no quadrilaterals: mesh the section's surfaces with quadrilaterals and put "
                     f"them in physical surfaces (gmsh saves only physical groups; {GMSH_QUADS})")
    if len(orders) > 1:
        raise refuse(f"mixes {counts['quad']} quad and {counts['quad9']} quad9 elements: make them "
                     "all one order (gmsh: Mesh.ElementOrder)")
    quads, lines, offset = [], [np.empty((0, 3), np.int64)], {}
    for k, block in enumerate(mesh.cells):
        data = np.asarray(block.data, np.int64)
        if block.type in QUADS:
            offset[k] = ("quad", sum(map(len, quads)))
            quads.append(data)
        elif block.type in CURVES:
            offset[k] = ("line", sum(map(len, lines)))
            lines.append(np.pad(data, ((0, 0), (0, 3 - data.shape[1])), constant_values=-1))
    groups = [(name, dim, offset[k][0], offset[k][1] + ids)
              for name, dim, k, ids in _physical(mesh) if k in offset]
    for name, value in mesh.field_data.items():
        tag, dim = (int(v) for v in value[:2])
        if dim in (1, 2) and not any(g[0] == name for g in groups):
            raise refuse(f"physical {'curve' if dim == 1 else 'surface'} {name!r} (tag {tag}) has no "
                         f"{'lines' if dim == 1 else 'quadrilaterals'}: mesh it, or delete the group")
    return np.concatenate(quads), np.concatenate(lines), groups


def _physical(mesh):
    """``(name, dim, block, indices)`` of each physical group's cells in each cell block.

    MSH 4.1 keeps a group's cells in meshio's ``cell_sets`` by name (an entity may be in several
    groups; ``gmsh:physical`` holds its first only); MSH 2.2 tags every cell, once per group
    (an element in two groups is written twice). Tag 0 is no group; a group without a name is
    named by its tag.
    """
    names = {(int(v[0]), int(v[1])): n for n, v in mesh.field_data.items()}
    if any(n in mesh.cell_sets for n in mesh.field_data):
        for name, v in mesh.field_data.items():
            for k, ids in enumerate(mesh.cell_sets.get(name, ())):
                if ids is not None and len(ids):
                    yield name, int(v[1]), k, np.asarray(ids, np.int64)
        return
    for k, tags in enumerate(mesh.cell_data.get("gmsh:physical", ())):
        dim = mesh.cells[k].dim
        for tag in np.unique(tags):
            if tag != 0:
                yield names.get((int(tag), dim), str(tag)), dim, k, np.flatnonzero(tags == tag)


def _quadratic(x, corners):
    """quad4 as 9-node geometry: a mid-side node per edge (shared), a centre per element."""
    key = np.sort(corners[:, EDGE_CORNERS], axis=-1).reshape(-1, 2)
    ends, edge_of = np.unique(key, axis=0, return_inverse=True)
    n, n_el = len(x), len(corners)
    x = np.concatenate([x, x[ends].mean(axis=1), x[corners].mean(axis=1)])
    mids = n + edge_of.reshape(n_el, 4)
    return x, np.concatenate([corners, mids, (n + len(ends) + np.arange(n_el))[:, None]], axis=1)


def _counter_clockwise(x, elements, refuse):
    """``elements`` with the clockwise ones mirrored; refuse one whose Jacobian is not positive
    at all its nodes (degenerate, non-convex or self-crossing)."""
    X = x[elements]
    gx, gy = np.meshgrid(GAUSS_1D, GAUSS_1D)
    area = jacobian(X, gx.ravel(), gy.ravel()) @ np.outer(WEIGHTS_1D, WEIGHTS_1D).ravel()
    elements = np.where((area < 0)[:, None], elements[:, MIRROR], elements)
    det = jacobian(x[elements], NODE_XI, NODE_ETA)
    bad = np.flatnonzero(np.any(det <= 1e-12 * np.abs(area)[:, None], axis=1))
    if len(bad):
        e = bad[0]
        node = elements[e, np.argmin(det[e])]
        more = f"; {len(bad)} elements in all" if len(bad) > 1 else ""
        raise refuse(f"element {e} (centre {_at(x[elements[e, 8]])}) is degenerate or inverted "
                     f"(det J <= 0 at its node {_at(x[node])}{more}): make it a convex quadrilateral "
                     "(gmsh: Mesh.Optimize, smaller elements along curved edges)")
    return elements


def _sides(elements) -> np.ndarray:
    """Every element's edges ``[a, mid, b]``, counter-clockwise: ``(n_el * 4, 3)``, row
    ``4 e + l`` local edge ``l`` of element ``e``."""
    corners = elements[:, EDGE_CORNERS]  # (n_el, 4, 2)
    return np.stack([corners[..., 0], elements[:, 4:8], corners[..., 1]], axis=-1).reshape(-1, 3)


def _check_nodes(x, elements, refuse):
    """Each node one role: a mid-side node shared by exactly the elements sharing its edge, a
    centre by no other element, no node both a corner and a mid-side (a hanging node); no edge
    on more than two elements, nor twice in one direction (overlapping elements)."""
    shared = np.flatnonzero(np.bincount(elements.ravel())[elements[:, 8]] > 1)
    if len(shared):
        e = shared[0]
        raise refuse(f"the centre node of element {e} at {_at(x[elements[e, 8]])} belongs to "
                     f"another element too: {CONFORM}")
    both = np.intersect1d(elements[:, :4], elements[:, 4:8])
    if len(both):
        raise refuse(f"node at {_at(x[both[0]])} is a corner of one element and a mid-side node of "
                     f"another (a hanging node): {CONFORM}")
    sides = _sides(elements)
    ends = np.sort(sides[:, [0, 2]], axis=1)
    pairs = np.unique(np.column_stack([ends, sides[:, 1]]), axis=0)  # sorted by the ends
    split = np.flatnonzero(np.all(pairs[1:, :2] == pairs[:-1, :2], axis=1))
    if len(split):
        a, b = pairs[split[0], :2]
        raise refuse(f"the elements on the edge from {_at(x[a])} to {_at(x[b])} have different "
                     f"mid-side nodes: {MERGE}")
    mids, count = np.unique(pairs[:, 2], return_counts=True)
    if np.any(count > 1):
        raise refuse(f"the mid-side node at {_at(x[mids[count > 1][0]])} is on two different element "
                     f"edges: {CONFORM}")
    directed, count = np.unique(sides[:, [0, 2]], axis=0, return_counts=True)
    edge, on = np.unique(ends, axis=0, return_counts=True)
    if np.any(count > 1) or np.any(on > 2):
        a, b = directed[count > 1][0] if np.any(count > 1) else edge[on > 2][0]
        raise refuse(f"elements overlap along the edge from {_at(x[a])} to {_at(x[b])}: mesh each "
                     "part of the section once")


def _check_hanging(x, elements, pieces, size, refuse):
    """Refuse an element corner lying in the interior of another element's edge (off its end
    nodes): the elements on either side would not share that corner's displacement. Only edges
    on one element are candidates (a conforming neighbour shares the corner). Between two
    bodies (pieces ``(n_el,)``) that touch, their nodes do not face each other there."""
    sides = _sides(elements)
    mids, count = np.unique(sides[:, 1], return_counts=True)
    alone = np.isin(sides[:, 1], mids[count == 1])
    seg, seg_piece = sides[alone], np.repeat(pieces, 4)[alone]
    a, m, b = x[seg[:, 0]], x[seg[:, 1]], x[seg[:, 2]]
    d1, d2 = (b - a) / 2, (a + b) / 2 - m  # the edge curve: m + s d1 + s^2 d2, s in [-1, 1]
    tol = OUTSIDE * size
    apex = 2 * m - (a + b) / 2  # the curve lies in the triangle a, apex, b
    box_lo = np.minimum(np.minimum(a, b), apex) - tol
    box_hi = np.maximum(np.maximum(a, b), apex) + tol
    corners = np.unique(seg[:, [0, 2]])
    chunk = max(1, 1_000_000 // max(1, len(seg)))
    for start in range(0, len(corners), chunk):
        node = corners[start:start + chunk]
        p = x[node]
        near = np.all((p[:, None] >= box_lo) & (p[:, None] <= box_hi), axis=-1)
        near &= (node[:, None] != seg[:, 0]) & (node[:, None] != seg[:, 2])
        i, e = np.nonzero(near)
        if not len(i):
            continue
        q, d1e, d2e, me = p[i], d1[e], d2[e], m[e]
        s = np.clip(_dot(q - me, d1e) / _dot(d1e, d1e), -1, 1)
        for _ in range(8):  # Newton on the squared distance to the curve
            r = me + s[:, None] * d1e + (s * s)[:, None] * d2e - q
            t = d1e + 2 * s[:, None] * d2e
            s = np.clip(s - _dot(r, t) / np.maximum(_dot(t, t) + 2 * _dot(r, d2e), 1e-300), -1, 1)
        gap = np.linalg.norm(me + s[:, None] * d1e + (s * s)[:, None] * d2e - q, axis=1)
        hang = np.flatnonzero((gap <= tol) & (np.linalg.norm(q - a[e], axis=1) > tol)
                              & (np.linalg.norm(q - b[e], axis=1) > tol))
        if len(hang):
            h = hang[0]
            where = f"element corner at {_at(q[h])} lies inside the element edge from {_at(a[e[h]])} to {_at(b[e[h]])}"
            if _node_labels(elements, pieces, len(x))[node[i[h]]] != seg_piece[e[h]]:
                raise refuse(f"{where} of another body: where two bodies touch, mesh their faces node for "
                             "node (gmsh: transfinite curves of one count), or make them one body (Coherence)")
            raise refuse(f"{where} (a hanging node): {CONFORM}")


def _dot(u, v) -> np.ndarray:
    """Row-wise dot products of ``(n, 2)`` arrays."""
    return np.einsum("nc,nc->n", u, v)


def _pieces(elements, n_nodes: int) -> np.ndarray:
    """The connected piece of each element, ``(n_el,)``: elements sharing a node are of one."""
    n_el = len(elements)
    el = np.repeat(np.arange(n_el), elements.shape[1])
    graph = sp.coo_matrix((np.ones(el.size), (el, n_el + elements.ravel())), shape=(n_el + n_nodes,) * 2)
    return connected_components(graph, directed=False)[1][:n_el]


def _node_labels(elements, labels, n_nodes: int) -> np.ndarray:
    """Each node's label of an element holding it (its piece: one for all), ``(n_nodes,)``."""
    out = np.full(n_nodes, -1, np.int64)
    out[elements] = np.asarray(labels)[:, None]
    return out


def _coincident(x, tol: float) -> np.ndarray:
    """The pairs of nodes within ``tol`` of each other in each coordinate, ``(n, 2)``, lower
    id first."""
    pairs = np.asarray(cKDTree(x).query_pairs(tol, p=np.inf, output_type="ndarray"), np.int64).reshape(-1, 2)
    return pairs[np.lexsort(pairs.T[::-1])]


def _check_coincident(x, n_file, elements, pieces, regions, size, refuse):
    """Refuse two of the file's nodes (the first ``n_file``) at one point in one piece (elements
    meeting there are not connected), or in two pieces of one physical surface (one body meshed
    twice, not joined). Nodes at one point in two pieces of two surfaces are two bodies that
    touch."""
    pairs = _coincident(x[:n_file], COINCIDENT * size)
    if not len(pairs):
        return
    piece = _node_labels(elements, pieces, len(x))[pairs]
    label = np.empty(len(elements), np.int64)
    for j, ids in enumerate(regions.values()):
        label[ids] = j
    surface = _node_labels(elements, label, len(x))[pairs]
    one = np.flatnonzero((piece[:, 0] == piece[:, 1]) | (surface[:, 0] == surface[:, 1]))
    if len(one):
        k = one[0]
        where = f"element edges at (x1, x2) = {_at(x[pairs[k, 0]])} are not connected"
        if piece[k, 0] == piece[k, 1]:
            raise refuse(f"{where} (a crack or duplicated nodes): {MERGE}")
        name = list(regions)[surface[k, 0]]
        raise refuse(f"{where} (a crack or duplicated nodes: two parts of {name!r} touch there): {MERGE}; "
                     "bodies that touch are physical surfaces of their own")


def _regions(x, elements, groups, refuse) -> dict[str, np.ndarray]:
    """Physical surface name -> sorted element ids; each element in one region, or all in
    ``"body"`` without physical surfaces. An element in two groups comes as two elements with
    the same nodes in MSH 2.2, as one in both groups' cell sets in MSH 4.1."""
    label = np.full(len(elements), -1)
    names = []
    for name, dim, kind, ids in groups:
        if kind != "quad" or dim != 2:
            continue
        if name not in names:
            names.append(name)
        j = names.index(name)
        clash = ids[(label[ids] >= 0) & (label[ids] != j)]
        if len(clash):
            e = clash[0]
            raise refuse(f"element {e} (centre {_at(x[elements[e, 8]])}) is in physical surfaces "
                         f"{names[label[e]]!r} and {name!r}: put each element in one")
        label[ids] = j
    corners = np.sort(elements[:, :4], axis=1)
    _, first, group, count = np.unique(corners, axis=0, return_index=True, return_inverse=True,
                                       return_counts=True)
    twice = np.flatnonzero(count[group.ravel()] > 1)
    if len(twice):
        f = twice[-1]
        e = first[group.ravel()[f]]
        where = " and ".join(repr(names[label[i]]) for i in (e, f) if label[i] >= 0)
        where = f" (in physical surfaces {where})" if where else ""
        raise refuse(f"elements {e} and {f} (centre {_at(x[elements[e, 8]])}) have the same nodes"
                     f"{where}: put each element in one physical surface, and mesh each part once")
    if not names:
        return {"body": np.arange(len(elements))}
    loose = np.flatnonzero(label < 0)
    if len(loose):
        raise refuse(f"{len(loose)} elements are in no physical surface (element {loose[0]}, centre "
                     f"{_at(x[elements[loose[0], 8]])}): add them to one, or save physical groups "
                     "only (gmsh: Mesh.SaveAll = 0)")
    return {name: np.flatnonzero(label == j) for j, name in enumerate(names)}


def _edges(x, elements, lines, groups, refuse):
    """Physical curve name -> segments ``[a, mid, b]`` (counter-clockwise round their owner),
    and owners: each line is the element edge with its end nodes (on an interior curve, the
    lower element's); a line in a group twice counts once."""
    sides = _sides(elements)
    key = np.array([len(x), 1])  # a node pair as one integer
    code = np.sort(sides[:, [0, 2]], axis=1) @ key
    order = np.argsort(code, kind="stable")  # the lower element first
    members = {}
    for name, dim, kind, ids in groups:
        if kind == "line" and dim == 1:
            members[name] = np.concatenate([members.get(name, ids[:0]), ids])
    edges, owners = {}, {}
    for name, ids in members.items():
        line = lines[ids]
        ends = np.sort(line[:, :2], axis=1)
        slot = order[np.minimum(np.searchsorted(code[order], ends @ key), len(code) - 1)]
        seg = sides[slot]
        miss = np.flatnonzero((ends[:, 0] < 0) | np.any(np.sort(seg[:, [0, 2]], axis=1) != ends, axis=1))
        if len(miss):
            at = " to ".join(_at(x[v]) if v >= 0 else "a node of no element" for v in line[miss[0], :2])
            raise refuse(f"a line of physical curve {name!r} (from {at}) is not an element edge: mesh "
                         "the curve as part of the section's boundary or interfaces (gmsh: Coherence)")
        off = np.flatnonzero((line[:, 2] >= 0) & (line[:, 2] != seg[:, 1]))
        if len(off):
            raise refuse(f"a line of physical curve {name!r} at {_at(x[seg[off[0], 1]])} has a mid node "
                         f"that is not the element edge's: {CONFORM}")
        _, first = np.unique(seg[:, 1], return_index=True)
        keep = np.sort(first)
        keep = keep[_chain(seg[keep])]
        edges[name], owners[name] = seg[keep], slot[keep] // 4
    return edges, owners


def _chain(seg) -> np.ndarray:
    """An order of segments ``[a, mid, b]`` in which each follows the one it starts at the end
    of, where one does: chains from the open ends first, then closed loops."""
    start_at = {a: i for i, a in reversed(list(enumerate(seg[:, 0].tolist())))}
    ends = set(seg[:, 2].tolist())
    seen = np.zeros(len(seg), bool)
    order = []
    for i in [i for i in range(len(seg)) if int(seg[i, 0]) not in ends] + list(range(len(seg))):
        while i is not None and not seen[i]:
            seen[i] = True
            order.append(i)
            i = start_at.get(int(seg[i, 2]))
    return np.array(order, np.int64)
