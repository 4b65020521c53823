"""Structured cross-section meshes of 4-node elements generated from a case's section block."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cases.geometry import Section


@dataclass(frozen=True)
class SectionMesh:
    """Quadrilateral mesh of a cross-section.

    Attributes
    ----------
    x : (n_nodes, 2) section coordinates (x1, x2) of the nodes
    st : (n_nodes, 2) parametric coordinates (s, t) of the nodes
    elements : (n_elements, 4) node indices, counter-clockwise in (s, t)
    shape : (n_s, n_t) numbers of elements along s and t
    section : the block it was generated from
    """

    x: np.ndarray
    st: np.ndarray
    elements: np.ndarray
    shape: tuple[int, int]
    section: Section

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
        return self.st[self.elements].mean(axis=1)

    def edge_nodes(self, name: str) -> np.ndarray:
        """Nodes on a named edge, ordered along it."""
        ns, nt = self.shape
        grid = np.arange(self.n_nodes).reshape(nt + 1, ns + 1)  # [t index, s index]
        edge = self.section.edge(name)
        return {"s_min": grid[:, 0], "s_max": grid[:, -1], "t_min": grid[0], "t_max": grid[-1]}[edge]

    def edge_segments(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """Segments ``(n_seg, 2)`` of node pairs on an edge and the element each belongs to."""
        nodes = self.edge_nodes(name)
        seg = np.column_stack([nodes[:-1], nodes[1:]])
        ns, nt = self.shape
        grid = np.arange(self.n_elements).reshape(nt, ns)
        edge = self.section.edge(name)
        owner = {"s_min": grid[:, 0], "s_max": grid[:, -1], "t_min": grid[0], "t_max": grid[-1]}[edge]
        return seg, owner

    def axis_nodes(self, tol: float = 1e-12) -> np.ndarray:
        """Nodes on the axis of revolution (x1 = r = 0)."""
        scale = np.abs(self.x).max()
        return np.flatnonzero(np.abs(self.x[:, 0]) <= tol * scale)


def section_mesh(section: Section, scale: float = 1, extra=((), ())) -> SectionMesh:
    """Tensor-product mesh of the block, each graded segment split ``scale`` times more, with
    the ``extra`` (s, t) points (the cut-outs' edges) as nodes (:meth:`cases.geometry.Axis.grid`)."""
    s, t = section.s.grid(scale, extra[0]), section.t.grid(scale, extra[1])
    S, T = np.meshgrid(s, t)  # [t index, s index]
    x1, x2 = section.to_x(S.ravel(), T.ravel())
    ns, nt = len(s) - 1, len(t) - 1
    i, j = np.meshgrid(np.arange(ns), np.arange(nt))
    n0 = (j * (ns + 1) + i).ravel()
    elements = np.column_stack([n0, n0 + 1, n0 + ns + 2, n0 + ns + 1])
    x = np.column_stack([x1, x2])
    # a polar block (s sin t, s cos t) is mirrored with respect to (s, t): keep the elements
    # counter-clockwise in (x1, x2) so that every Jacobian is positive
    e = x[elements]
    area2 = (e[:, 2, 0] - e[:, 0, 0]) * (e[:, 3, 1] - e[:, 1, 1]) - (e[:, 3, 0] - e[:, 1, 0]) * (e[:, 2, 1] - e[:, 0, 1])
    if np.all(area2 < 0):
        elements = elements[:, [0, 3, 2, 1]]
    return SectionMesh(x, np.column_stack([S.ravel(), T.ravel()]), elements, (ns, nt), section)
