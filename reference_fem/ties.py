"""Nodes tied on the axis: a mesh section that reaches the axis, swept round it into hexahedra.

Sweeping a section element that has an edge on the axis (r = 0) round the axis gives a
27-node hexahedron whose face on that edge is a line: its 9 nodes stand at 3 points of the
axis, 3 angles each. The mesh keeps those nodes apart, one per angle (its topology is that of
any ring swept round the axis: each such node is shared by the two elements next to it round
the axis, so every face has one or two elements, as scikit-fem's facets need), and ties them
here: every node at one point of the axis (of one body) is one unknown. So the displacement on
the axis is single-valued, and each element round it is the collapsed hexahedron of Irons'
degenerate elements: its shape functions at one axis point summed into one.

Why this is sound:

* The element is isoparametric: the tied functions sum to one and interpolate x exactly as the
  untied ones did, so a field linear in x (any rigid motion, any uniform strain) is in the
  space, and the patch test holds (tests/test_reference_axis.py).
* The map's Jacobian vanishes on the axis face only (it is proportional to the distance from
  the axis, as in polar coordinates): the quadrature points are inside the element, where it
  is positive, and the strain is bounded (the field's derivative round the axis vanishes with
  that distance, because the axis nodes are one).
* The facets on the axis are lines, of zero area: no load, support or face lies on them
  (:func:`reference_fem.swept.edge_facets` leaves them out).

The ties are a renumbering of scikit-fem's dofs (:func:`dofs`), so every basis of the mesh
(:func:`cell_basis`, :func:`facet_basis`) assembles on the tied unknowns and nothing downstream
(mass, stiffness, supports, probes, contact faces) knows of them. A mesh's nodes
(``mesh.doflocs``) stay untied; :func:`node_positions` gives those of the unknowns.
"""

from __future__ import annotations

import numpy as np
from skfem import CellBasis, FacetBasis
from skfem.assembly import Dofs


def tie_coincident(points: np.ndarray, element_nodes: np.ndarray, groups: np.ndarray | None,
                   scale: float) -> np.ndarray:
    """For each node of ``points`` (dim, n), the first node at its point (within 1e-9
    ``scale``) in the same group: ``groups`` (n_elements,), the group of each element of
    ``element_nodes`` (nodes per element, n_elements), or None for one group."""
    group = np.zeros(points.shape[1], np.int64)
    if groups is not None:
        group[element_nodes] = np.asarray(groups, np.int64)[None, :]
    key = np.vstack([np.round(points / (1e-9 * scale)).astype(np.int64), group[None, :]])
    _, first, inverse = np.unique(key.T, axis=0, return_index=True, return_inverse=True)
    return first[inverse.ravel()]


def node_ids(mesh) -> tuple[np.ndarray, int] | None:
    """``(ids, n)``: the unknown (of ``n``) each node of ``mesh`` is, or None where no node is
    tied (every mesh but a swept section that reaches the axis)."""
    ties = getattr(mesh, "ties", None)
    if ties is None:
        return None
    cached = getattr(mesh, "_tied_ids", None)
    if cached is None:
        kept, ids = np.unique(ties, return_inverse=True)
        cached = ids.ravel(), len(kept)
        object.__setattr__(mesh, "_tied_ids", cached)
    return cached


def dofs(mesh, elem) -> Dofs | None:
    """scikit-fem's dofs of ``elem`` on ``mesh`` with the tied nodes' made one, or None (the
    default dofs) where nothing is tied. A dof of an element with ``k`` dofs per node is
    ``k node + component``, nodes numbered as ``mesh.doflocs``: renumbered node by node."""
    tied = node_ids(mesh)
    if tied is None:
        return None
    ids, n = tied
    out = Dofs(mesh, elem)
    k = out.nodal_dofs.shape[0]

    def renumber(a: np.ndarray) -> np.ndarray:
        return (k * ids[a // k] + a % k).astype(a.dtype) if a.size else a

    out.nodal_dofs, out.edge_dofs = renumber(out.nodal_dofs), renumber(out.edge_dofs)
    out.facet_dofs, out.interior_dofs = renumber(out.facet_dofs), renumber(out.interior_dofs)
    out.element_dofs = renumber(out.element_dofs)
    out.N = k * n
    return out


def cell_basis(mesh, elem, **kwargs) -> CellBasis:
    """``skfem.CellBasis`` on the tied unknowns (:func:`dofs`)."""
    return CellBasis(mesh, elem, dofs=dofs(mesh, elem), **kwargs)


def facet_basis(mesh, elem, **kwargs) -> FacetBasis:
    """``skfem.FacetBasis`` on the tied unknowns (:func:`dofs`)."""
    return FacetBasis(mesh, elem, dofs=dofs(mesh, elem), **kwargs)


def node_positions(mesh) -> np.ndarray:
    """Positions ``(dim, n_unknown_nodes)`` of the unknowns' nodes: ``mesh.doflocs``, each tied
    node once."""
    tied = node_ids(mesh)
    if tied is None:
        return mesh.doflocs
    ids, n = tied
    x = np.empty((mesh.doflocs.shape[0], n))
    x[:, ids] = mesh.doflocs
    return x


def of(mesh, nodes: np.ndarray) -> np.ndarray:
    """The unknowns' nodes (:func:`node_positions`) of ``mesh``'s nodes ``nodes``."""
    tied = node_ids(mesh)
    return np.asarray(nodes) if tied is None else tied[0][nodes]


def cells(mesh) -> np.ndarray:
    """The elements' nodes ``(nodes per element, n_elements)`` as unknowns' nodes
    (:func:`node_positions`), in scikit-fem's order."""
    return of(mesh, mesh.dofs.element_dofs)
