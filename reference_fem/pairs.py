"""Contact between two deformable bodies: the reference's node-to-node contact pairs.

A scene of several bodies (:mod:`cases.bodies`) is meshed with no node shared between bodies
(:func:`reference_fem.swept.pieces`), so the two faces of a pair (:class:`cases.geometry.ContactPair`)
are two rows of nodes. The meshes of the two faces are conforming by construction (one section
refined alike, swept alike in 3D), so every node ``i`` of the pair's ``face`` has one node ``j``
of ``other`` straight across it along the face's outward normal ``n_i``; :func:`match` finds it
in the reference's own mesh (not through the section's pairing), with the initial gap
``g0 = n_i . (x_j - x_i)``.

Implicit (:func:`case_pair_rows`): Lagrange multipliers on the relative displacement of each
pair of nodes, the rigid wall's rows and active set generalised (:func:`reference_fem.contact.wall_rows`
with ``others``; :class:`reference_fem.contact.WallContact` as it is): the normal row
``n . (u_j - u_i)`` with the gap ``g = g0 + n . (u_j - u_i) >= 0``, tangential rows of the
relative displacement, Coulomb friction as at a wall. The forces are equal and opposite on the
two nodes, so the bodies' total momentum is kept to round-off. The mass of both faces is
redistributed as at a wall (:mod:`reference_fem.mass`: massless face nodes). Node-to-node
contact holds for small sliding: the pairs are those of the undeformed mesh.

The explicit engine's pairs are in :mod:`reference_fem.explicit` (a kinematic correction split
by the two nodes' lumped masses), on the same :func:`match`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from cases.params import UnsupportedCase

from . import swept
from .contact import WallRows, wall_rows
from .face import face_of
from .frames import AXISYMMETRIC
from .wall import PENETRATION_TOL, ContactLog

#: a node of ``other`` is across a node of ``face`` when it is off the face normal there by less
#: than this share of the spacing of the other face's nodes
ACROSS = 0.25
#: face nodes matched per block (a dense block of distances: memory bounded in 3D)
BLOCK = 512


@dataclass(frozen=True)
class Matched:
    """The node pairs of one contact pair of a model's mesh.

    Attributes
    ----------
    nodes : (n,) the nodes of the pair's ``face``
    others : (n,) the node of ``other`` across each
    normals : (n, dim) the face's outward unit normal at each node (mesh frame)
    g0 : (n,) initial gaps ``n . (x_other - x_node)`` (m; negative: an overlap)
    friction : the pair's Coulomb coefficient (of all pairs, :func:`all_pairs`: one per node)
    area : the face's area (m^2, per radian when axisymmetric)
    """

    nodes: np.ndarray
    others: np.ndarray
    normals: np.ndarray
    g0: np.ndarray
    friction: float | np.ndarray
    area: float


def match(model, pair) -> Matched:
    """The node of ``pair.other`` straight across every node of ``pair.face`` in ``model``'s mesh
    (off the face's normal by less than :data:`ACROSS` of the other face's node spacing, the
    nearest along it, one each), or :class:`UnsupportedCase` in one line where the two faces are
    not node for node."""
    x = model.nodes_x
    face = face_of(model, pair.face)
    normals = np.where(np.abs(face.normals) > 1e-12, face.normals, 0.0)  # round-off of a plane's normal
    normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    other = face_of(model, pair.other).nodes
    xo = x[:, other].T
    spacing = cKDTree(xo).query(xo, k=2)[0][:, 1].min()
    best = np.empty(face.nodes.size, int)
    along = np.empty(face.nodes.size)
    sideways = np.empty(face.nodes.size)
    for start in range(0, face.nodes.size, BLOCK):
        rows = slice(start, start + BLOCK)
        d = xo[None, :, :] - x[:, face.nodes[rows]].T[:, None, :]  # (block, n_other, dim)
        a = np.einsum("fok,fk->fo", d, normals[rows])
        off = np.linalg.norm(d - a[..., None] * normals[rows, None, :], axis=2)
        # on the normal line, the nearest (a curved face's line meets the other face twice)
        k = np.argmin(np.where(off <= ACROSS * spacing, np.abs(a), np.inf), axis=1)
        r = np.arange(k.size)
        best[rows], along[rows], sideways[rows] = k, a[r, k], off[r, k]
    bad = np.flatnonzero(sideways > ACROSS * spacing)
    if bad.size or np.unique(best).size != best.size:
        i = bad[0] if bad.size else int(np.flatnonzero(np.bincount(best)[best] > 1)[0])
        where = ", ".join(f"{v:.6g}" for v in x[:, face.nodes[i]])
        raise UnsupportedCase(f"reference solver: contact pair {pair.face} / {pair.other}: no node of {pair.other} "
                              f"lies across the node of {pair.face} at ({where}) alone: the faces are not meshed "
                              "node for node")
    return Matched(face.nodes, other[best], normals, along, float(pair.friction), face.area)


def all_pairs(model) -> Matched:
    """Every contact pair of ``model.case`` matched (:func:`match`), as one: their node pairs one
    after another, ``friction`` one per node (n,), ``area`` the faces' sum."""
    pairs = [match(model, pair) for pair in model.case.contacts]
    join = lambda name: np.concatenate([getattr(m, name) for m in pairs])  # noqa: E731
    return Matched(join("nodes"), join("others"), join("normals"), join("g0"),
                   np.concatenate([np.full(m.nodes.size, m.friction) for m in pairs]), sum(m.area for m in pairs))


def case_pair_rows(model) -> WallRows:
    """The constraint rows of all of ``model.case``'s contact pairs (module docstring): their
    normal rows, then (where any pair has friction) their tangential rows, node by node."""
    m = all_pairs(model)
    size = np.abs(model.rmesh.mesh.p).max()
    try:
        return wall_rows(m.nodes, m.normals, m.g0, model.free, model.basis.N, m.friction, PENETRATION_TOL * size,
                         others=m.others)
    except ValueError:
        raise UnsupportedCase("reference solver: no node of a contact pair's faces can move along their normal "
                              "(both supported)") from None


def held_by_supports(model) -> None:
    """Refuse (:class:`UnsupportedCase`, one line) a static solve in which a body of the scene
    could move as a rigid body but for its contacts: its stiffness is then singular (a body held
    by contact alone has no static state here). The rigid motions of a piece of the mesh are
    the translations and rotations its representation has (axisymmetric: the axial translation
    only); they are held where the supported dofs leave none of them free."""
    dim, x = model.dim, model.nodes_x
    if model.rep == AXISYMMETRIC:
        modes = [np.array([0.0, 1.0])[:, None] * np.ones_like(x[0])]
    else:
        modes = [np.eye(dim)[:, k : k + 1] * np.ones_like(x[0]) for k in range(dim)]
        pairs = [(0, 1)] if dim == 2 else [(0, 1), (1, 2), (2, 0)]
        for i, j in pairs:
            rot = np.zeros_like(x)
            rot[i], rot[j] = -x[j], x[i]
            modes.append(rot)
    R = np.stack([m.T.ravel() for m in modes], axis=1)  # (n_dof, k), node-major
    fixed = np.zeros(model.basis.N, bool)
    fixed[model.fixed] = True
    section = model.rmesh.section
    piece = swept.pieces(section)[model.rmesh.parent]
    for k in np.unique(piece):
        dofs = np.unique(model.basis.element_dofs[:, piece == k])
        held = R[dofs[fixed[dofs]]]
        scale = np.abs(R[dofs]).max(axis=0)
        if held.shape[0] and np.linalg.matrix_rank(held / scale, tol=1e-9 * np.sqrt(held.shape[0])) == R.shape[1]:
            continue
        elements = np.flatnonzero(piece == k)
        name = next((n for n, e in section.regions.items() if np.isin(model.rmesh.parent[elements], e).all()),
                    f"piece {k}")
        raise UnsupportedCase(f"reference solver: {model.case.name}: body {name!r} is held by its contact alone (its "
                              "supports leave it a rigid motion): a static solve with contact pairs needs every body "
                              "supported on its own")


class PairLog(ContactLog):
    """Per-step diagnostics of a run with contact pairs, for ``ReferenceResult.info``: the
    wall's (:class:`reference_fem.wall.ContactLog`: energy, contact window, largest penetration,
    here of the pairs' nodes into each other), the total momentum and the largest numbers of
    nodes closed, sticking and slipping at any one step.

    Momentum: ``M v`` summed per mesh component (kg m/s, times 2 pi when axisymmetric, where
    only the axial component, index 1, is a momentum); kept to round-off by equal and opposite
    contact forces where no support or load acts along a component.
    """

    def __init__(self, system, per_radian: bool):
        super().__init__(system, per_radian)
        self.counts = np.zeros(3, int)  # the largest number of nodes open, sticking, slipping at once
        self.closed = 0  # and closed (sticking or slipping; frictionless: closed is STICK)
        self.pairs = len(system.model.case.contacts)

    def record(self, t: float, u: np.ndarray, v: np.ndarray, u_full: np.ndarray) -> None:
        super().record(t, u, v, u_full)
        s = self.system
        count = np.bincount(s.state.state, minlength=3)[:3]
        self.counts = np.maximum(self.counts, count)
        self.closed = max(self.closed, count[1] + count[2])

    def clearance(self, u_full: np.ndarray) -> float:
        """The smallest gap between the pairs' nodes (m), negative where they overlap."""
        rows = self.system.rows
        return float((rows.g0 + rows.H[: rows.n_c] @ u_full[self.system.model.free]).min())

    def momentum(self, v: np.ndarray) -> np.ndarray:
        """``M v`` summed per mesh component, of the free dofs' velocity ``v``."""
        s = self.system
        full = np.zeros(s.model.basis.N)
        full[s.model.free] = s.M @ v
        return self.factor * full.reshape(-1, s.model.dim).sum(axis=0)

    def info(self) -> dict:
        out = super().info()
        out.update(contact_pairs=self.pairs, momentum_before=self.momentum(self.first[1]).tolist(),
                   momentum_after=self.momentum(self.last[1]).tolist(), most_nodes_closed=int(self.closed),
                   most_nodes_stick=int(self.counts[1]), most_nodes_slip=int(self.counts[2]))
        return out
