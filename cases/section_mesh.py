"""The section protocol: what every solver reads of a cross-section, whatever made it.

A section (:class:`cases.geometry.Section`, a mapped block; :class:`cases.msh_section.MeshSection`,
a gmsh mesh) gives, through its ``mesh(scale, extra, order)``, a :class:`SectionMesh`: nodes,
quadrilaterals of 4 nodes or (``order=2``) 9, named edges as segments with the element each
belongs to, named regions, and parametric coordinates (s, t) of the nodes (a mesh section's are
its (x1, x2)). No solver builds a section's mesh itself.

A mapped block's mesh is structured: 4-node elements, or 9-node ones on the grid refined once in
(s, t), whose mid-side nodes lie on the section's curved edges (they are mapped from (s, t)
like the corners)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .params import UnsupportedCase


@dataclass(frozen=True)
class SectionMesh:
    """Quadrilateral mesh of a cross-section.

    Attributes
    ----------
    x : (n_nodes, 2) section coordinates (x1, x2) of the nodes
    st : (n_nodes, 2) parametric coordinates (s, t) of the nodes
    elements : (n_elements, nodes) node indices: the corners counter-clockwise first
        (order 2: then the mid-sides of edges 0-1, 1-2, 2-3, 3-0 and the centre)
    shape : (n_s, n_t) numbers of elements along s and t of a mapped block; None for a mesh
    section : the section it was generated from
    order : 1 (corner nodes) or 2 (9 nodes per element)
    edges : a mesh section's named edges: name -> (segments (n_seg, order + 1), owners (n_seg,))
        (:meth:`edge_segments`); a mapped block's come from its grid
    regions : a mesh section's physical surfaces: name -> element ids
    """

    x: np.ndarray
    st: np.ndarray
    elements: np.ndarray
    shape: tuple[int, int] | None
    section: object
    order: int = 1
    edges: dict = field(default_factory=dict)
    regions: dict = field(default_factory=dict)

    @property
    def n_nodes(self) -> int:
        return len(self.x)

    @property
    def n_elements(self) -> int:
        return len(self.elements)

    def element_x(self) -> np.ndarray:
        """(n_elements, 4, 2) nodal coordinates per element."""
        return self.x[self.elements]

    def element_st_centres(self) -> np.ndarray:
        """(n_elements, 2) parametric coordinates of the element centres."""
        return self.st[self.elements[:, :4]].mean(axis=1)

    def edge_nodes(self, name: str) -> np.ndarray:
        """Nodes on a named edge (mid-side nodes included): a mapped block's ordered along it,
        a mesh section's by number."""
        if self.shape is None:
            return np.unique(self.edge_segments(name)[0])
        ns, nt = self.shape
        grid = np.arange(self.n_nodes).reshape(self.order * nt + 1, self.order * ns + 1)  # [t index, s index]
        edge = self.section.edge(name)
        return {"s_min": grid[:, 0], "s_max": grid[:, -1], "t_min": grid[0], "t_max": grid[-1]}[edge]

    def edge_segments(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Segments ``(n_seg, order + 1)`` of an edge's nodes, ordered along it (a quadratic
        segment's mid-side node in the middle), and the element each belongs to."""
        if self.shape is None:
            if name not in self.edges:
                raise UnsupportedCase(f"the section mesh has no edge {name!r} (its physical curves: {', '.join(self.edges)})")
            return self.edges[name]
        nodes = self.edge_nodes(name)
        k = self.order
        seg = np.column_stack([nodes[j:len(nodes) - k + j:k] for j in range(k + 1)])
        ns, nt = self.shape
        grid = np.arange(self.n_elements).reshape(nt, ns)
        edge = self.section.edge(name)
        owner = {"s_min": grid[:, 0], "s_max": grid[:, -1], "t_min": grid[0], "t_max": grid[-1]}[edge]
        return seg, owner

    def axis_nodes(self, tol: float = 1e-12) -> np.ndarray:
        """Nodes on the axis of revolution (x1 = r = 0)."""
        scale = np.abs(self.x).max()
        return np.flatnonzero(np.abs(self.x[:, 0]) <= tol * scale)


#: per order, the grid offsets (along s, along t) of an element's nodes, in the node order of
#: :class:`SectionMesh` (order 2: :data:`smfem.quad9.NODE_I`, ``NODE_J``), and the same nodes
#: clockwise (a mirrored block)
NODE_OFFSETS = {1: (np.array([0, 1, 1, 0]), np.array([0, 0, 1, 1])),
                2: (np.array([0, 2, 2, 0, 1, 2, 1, 0, 1]), np.array([0, 0, 2, 2, 0, 1, 2, 1, 1]))}
MIRRORED = {1: [0, 3, 2, 1], 2: [0, 3, 2, 1, 7, 6, 5, 4, 8]}


def _refined(grid: np.ndarray, order: int) -> np.ndarray:
    """The grid with ``order - 1`` equally spaced points inserted in every interval."""
    fractions = np.arange(order) / order
    inner = grid[:-1, None] + fractions[None, :] * np.diff(grid)[:, None]
    return np.append(inner.ravel(), grid[-1])


def section_mesh(section, scale: float = 1, extra=((), ()), order: int = 1) -> SectionMesh:
    """The mesh of any section (the protocol's one entry): ``scale`` times its element counts
    (a mesh section: an integer, each element split scale x scale), the ``extra`` (s, t) points
    of a mapped block as grid nodes, elements of 4 nodes or (``order=2``) 9."""
    return section.mesh(scale, extra, order)


def block_mesh(section, scale: float = 1, extra=((), ()), order: int = 1) -> SectionMesh:
    """Tensor-product mesh of the block, each graded segment split ``scale`` times more, with
    the ``extra`` (s, t) points (the cut-outs' edges) as nodes (:meth:`cases.geometry.Axis.grid`);
    ``order=2``: the same elements with 9 nodes each (mid-sides and centre at the middles in (s, t))."""
    s, t = section.s.grid(scale, extra[0]), section.t.grid(scale, extra[1])
    ns, nt = len(s) - 1, len(t) - 1
    S, T = np.meshgrid(_refined(s, order), _refined(t, order))  # [t index, s index]
    x1, x2 = section.to_x(S.ravel(), T.ravel())
    width = order * ns + 1
    i, j = np.meshgrid(np.arange(ns), np.arange(nt))
    n0 = (order * j * width + order * i).ravel()
    di, dj = NODE_OFFSETS[order]
    elements = n0[:, None] + dj[None, :] * width + di[None, :]
    x = np.column_stack([x1, x2])
    # a polar block (s sin t, s cos t) is mirrored with respect to (s, t): keep the elements
    # counter-clockwise in (x1, x2) so that every Jacobian is positive
    e = x[elements]
    area2 = (e[:, 2, 0] - e[:, 0, 0]) * (e[:, 3, 1] - e[:, 1, 1]) - (e[:, 3, 0] - e[:, 1, 0]) * (e[:, 2, 1] - e[:, 0, 1])
    if np.all(area2 < 0):
        elements = elements[:, MIRRORED[order]]
    return SectionMesh(x, np.column_stack([S.ravel(), T.ravel()]), elements, (ns, nt), section, order)


def unstructured_mesh(section, scale: float = 1, extra=((), ()), order: int = 1) -> SectionMesh:
    """The mesh of a mesh section (:class:`cases.msh_section.MeshSection`): each element split
    ``scale`` x ``scale`` (a whole number: a mesh cannot be coarsened), with 4 or 9 nodes. Its
    parametric coordinates are (x1, x2); ``extra`` grid points mean nothing to it."""
    k = int(round(scale))
    if k < 1 or abs(scale - k) > 1e-9:
        raise UnsupportedCase(f"a mesh section is refined by a whole factor (refine = k splits each element k x k); "
                              f"it cannot be coarsened or scaled by {scale:g}")
    fine = section.refined(k)
    x, elements, edges = fine.at_order(order)
    return SectionMesh(x, x.copy(), elements, None, section, order, edges, dict(fine.regions))
