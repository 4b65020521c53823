"""Node-to-rigid-wall and node-to-node contact: Lagrange multipliers, primal-dual active set,
Coulomb friction.

Each contact node ``i`` has a normal row and (with friction) ``dim - 1`` tangential rows of the
constraint matrix ``H`` (free dofs): ``y = H u`` are the node's displacement away from the wall
(``-n . u_i``) and along the tangents, and ``f = H^T p`` the wall's forces on the body, so
``p_n = lambda_i >= 0`` is the normal reaction and ``p_t = tau_i`` the friction force.
The gap is ``g_i = g0_i + y_n,i >= 0``. Between two bodies (a contact pair, node ``i`` of one
face and node ``j`` across it on the other, :mod:`reference_fem.pairs`) the rows are the same
rows of the relative displacement ``u_i - u_j``: ``y_n = n . (u_j - u_i)``, the forces ``H^T p``
equal and opposite on the two nodes (momentum is kept), ``n`` the face's outward normal at ``i``.

One step solves ``A u = b + H^T p`` with ``A = K + a0 M`` factorized once. With
``u* = A^{-1} b`` and ``W = A^{-1} H^T`` (one back-substitution per row, once),
``y = H u* + S p`` and ``S = H W`` is a small dense matrix on the contact rows: the contact
problem of a step lives on those rows only (a Schur complement), and ``u = u* + W p``.

States, re-evaluated from the augmented forces (Alart-Curnier; Hueber, Stadler & Wohlmuth 2008)
``lambda~ = lambda - c g`` and ``tau~ = tau - c s`` (``s`` the tangential slip of the step):
open (``lambda~ <= 0``: ``p = 0``), stick (``|tau~| <= f lambda~``: ``g = 0``, ``s = 0``), slip
(``g = 0``, ``tau = -f lambda s^``, ``s^ = -tau~ / |tau~|``, linearized about the previous
iterate in 3D). For a fixed state every condition is linear in ``p``; the state is iterated
until it repeats (in 3D also the slip directions).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .equilibrium import NotConverged
from .face import tangent_basis, tangent_bases

OPEN, STICK, SLIP = 0, 1, 2
#: active-set iterations allowed per step before the state counts as chattering
MAX_ITERATIONS = 50
#: a slip direction that moves less than this between iterates has settled
DIRECTION_TOL = 1e-8
#: hysteresis of the stick/slip switch, relative to the friction limit: a node at the limit of
#: the friction cone with no slip (degenerate, e.g. at the edge of a slip zone) would otherwise
#: flip between the two states on round-off
FRICTION_RTOL = 1e-5


class ContactNotSettled(NotConverged):
    """The open/stick/slip state of a step cycles or does not settle."""


@dataclass(frozen=True)
class WallRows:
    """Contact constraint rows of a rigid plane wall.

    Attributes
    ----------
    H : csr_matrix, ``(n_c (1 + n_tan), n_free)``: the normal rows of the ``n_c`` contact nodes,
        then ``n_tan`` tangential rows per node, node by node (``n_tan = 0`` when frictionless)
    g0 : (n_c,) initial gaps (m)
    nodes : (n_c,) mesh node of each contact node
    friction : Coulomb coefficient f: one, or one per contact node (n_c,)
    tol : penetration (and slip) tolerance (m), round-off level
    others : (n_c,) the node across each contact node on the other body of a pair; None at a wall
    """

    H: sp.csr_matrix
    g0: np.ndarray
    nodes: np.ndarray
    friction: float | np.ndarray
    tol: float
    others: np.ndarray | None = None

    @property
    def n_c(self) -> int:
        return self.g0.size


@dataclass
class ContactState:
    """Contact forces and states of one step (see the module docstring)."""

    p: np.ndarray  # (n_c + n_t,) normal reactions, then friction forces (N; per radian if axisym.)
    state: np.ndarray  # (n_c,) OPEN, STICK or SLIP
    direction: np.ndarray  # (n_c, dim - 1) slip direction in the tangent plane (zero unless SLIP)
    kappa: np.ndarray  # (n_c,) f lambda / |tau~| of slipping nodes: weight of the direction's change


#: the rows of the contact's Schur complement solved together (a dense block of this many columns)
ROW_BLOCK = 64


class WallContact:
    """The contact problem of one time step on the Schur complement of ``A`` (see module doc).

    Parameters
    ----------
    lu : factorization of ``A`` (``lu.solve``), free dofs
    rows : :class:`WallRows`
    """

    def __init__(self, lu, rows: WallRows):
        self.rows = rows
        H = rows.H
        # in blocks of rows: SuperLU's multi-column solve is twice as fast as one row at a time
        # (ring_in_ring in 3D, 1152 rows: 6.5 s against 13); its BLAS runs on the one thread
        # every entry point pins (smfem.runs.threads), for threaded BLAS stalls on a busy machine
        self.W = np.column_stack([lu.solve(H[k:k + ROW_BLOCK].T.toarray()) for k in range(0, H.shape[0], ROW_BLOCK)]) \
            if H.shape[0] else np.zeros((H.shape[1], 0))
        S = H @ self.W
        self.S = 0.5 * (S + S.T)
        n_c = rows.n_c
        self.n_tan = H.shape[0] // n_c - 1
        self.tan_rows = n_c + np.arange(n_c * self.n_tan).reshape(n_c, self.n_tan)
        # tangent rows without a free dof (the axis node's radial one) carry no friction force
        self.live = np.diff(H.indptr)[self.tan_rows] > 0
        # augmentation by each row's own compliance, so that c g and c s are forces
        d = np.diag(self.S)
        self.c = 1.0 / np.where(d > 0, d, 1.0)
        self.friction = np.broadcast_to(np.asarray(rows.friction, float), (n_c,))

    def initial(self) -> ContactState:
        n_c = self.rows.n_c
        return ContactState(np.zeros(self.S.shape[0]), np.full(n_c, OPEN), np.zeros((n_c, self.n_tan)), np.zeros(n_c))

    def solve(self, y_star: np.ndarray, y_prev: np.ndarray, last: ContactState) -> tuple[ContactState, int]:
        """Contact forces of one step.

        Parameters
        ----------
        y_star : (n_rows,) ``H u*`` of the unconstrained solution
        y_prev : (n_rows,) ``H u`` at the start of the step (slip is measured from it)
        last : the previous step's state: the first guess of this one

        Returns
        -------
        ContactState, and the number of linear solves (active-set iterations)

        Raises
        ------
        ContactNotSettled
            when the state returns to an earlier one (a cycle) or has not settled after
            :data:`MAX_ITERATIONS`.
        """
        current = last
        seen = [current]
        for it in range(1, MAX_ITERATIONS + 1):
            p = self._forces(current, y_star, y_prev)
            new = self._states(p, y_star + self.S @ p, y_prev, current)
            if _same(new, current):
                return ContactState(p, current.state, current.direction, current.kappa), it
            if any(_same(new, old) for old in seen[:-1]):
                raise ContactNotSettled(f"contact state chatters: iteration {it} returns to an earlier "
                                        f"state (nodes {self._flipped(new, current)} flip)")
            seen.append(new)
            current = new
        raise ContactNotSettled(f"contact state has not settled in {MAX_ITERATIONS} iterations "
                                f"(nodes {self._flipped(new, current)} still flip)")

    def _flipped(self, a: ContactState, b: ContactState) -> list[int]:
        return self.rows.nodes[a.state != b.state].tolist()

    def _states(self, p, y, y_prev, current: ContactState) -> ContactState:
        """The state each node's augmented forces ask for (module docstring) after ``current``."""
        rows = self.rows
        n_c = rows.n_c
        g = rows.g0 + y[:n_c]
        lam_aug = p[:n_c] - self.c[:n_c] * g
        closed = lam_aug > self.c[:n_c] * rows.tol
        state = np.where(closed, STICK, OPEN)
        direction, kappa = np.zeros_like(current.direction), np.zeros(n_c)
        if self.n_tan:
            t = self.tan_rows
            tau_aug = p[t] - self.c[t] * (y[t] - y_prev[t])
            size = np.linalg.norm(tau_aug, axis=1)
            band = np.where(current.state == SLIP, -FRICTION_RTOL, FRICTION_RTOL)
            limit = self.friction * lam_aug * (1 + band) + self.c[t].max(axis=1) * rows.tol
            slip = closed & (size > limit)
            state[slip] = SLIP
            direction[slip] = -tau_aug[slip] / size[slip, None]
            kappa[slip] = np.clip(self.friction[slip] * p[:n_c][slip] / size[slip], 0.0, 1.0)
        return ContactState(p, state, direction, kappa)

    def _forces(self, s: ContactState, y_star, y_prev) -> np.ndarray:
        """Solve the linear conditions of the states ``s`` for the contact forces ``p``."""
        n_c, S = self.rows.n_c, self.S
        E = np.eye(S.shape[0])
        rhs = np.zeros(S.shape[0])
        closed = np.flatnonzero(s.state != OPEN)
        E[closed] = S[closed]
        rhs[closed] = -self.rows.g0[closed] - y_star[closed]  # g = 0
        if self.n_tan:
            t = self.tan_rows
            stick = t[(s.state == STICK)[:, None] & self.live]
            E[stick] = S[stick]
            rhs[stick] = y_prev[stick] - y_star[stick]  # no slip
            slip = np.flatnonzero(s.state == SLIP)
            ts, d = t[slip], s.direction[slip]
            # tau = -f lambda s^(tau~), linearized (Newton) about the last iterate: the change of
            # the direction s^ weighs kappa P (tau - c slip), P the projection normal to s^
            # (Hueber, Stadler & Wohlmuth 2008); in 2D P = 0 and the rows are exact
            kP = s.kappa[slip, None, None] * (np.eye(self.n_tan) - np.einsum("ka,kb->kab", d, d))
            kPC = kP * self.c[ts][:, None, :]
            E[ts] = np.einsum("kab,kbm->kam", kPC, S[ts])
            E[ts[:, :, None], ts[:, None, :]] += np.eye(self.n_tan) - kP
            E[ts, slip[:, None]] += self.friction[slip, None] * d
            rhs[ts] = -np.einsum("kab,kb->ka", kPC, y_star[ts] - y_prev[ts])
        return np.linalg.solve(E, rhs)


def wall_rows(nodes: np.ndarray, normal: np.ndarray, g0: np.ndarray, free: np.ndarray, n_dof: int,
              friction: float | np.ndarray, tol: float, others: np.ndarray | None = None) -> WallRows:
    """Constraint rows of mesh ``nodes`` against a plane wall; ``normal`` is the body's outward one.

    Dofs are node-major (``node * dim + component``, scikit-fem's vector elements); rows act on
    the ``free`` dofs (a fixed component does not move). A node whose normal component is
    fixed cannot reach the wall and is left out. Tangential rows only with friction.

    Between two bodies, ``others`` (n_c,) is the node across each of ``nodes`` (a contact pair,
    :mod:`reference_fem.pairs`): the rows act on the relative displacement ``u_node - u_other``,
    ``normal`` may be one per node ``(n_c, dim)`` (a curved face) and ``friction`` one per node;
    a pair is left out where neither node can move along the normal.
    """
    normals = np.atleast_2d(normal)  # (1 or n_c, dim)
    dim = normals.shape[1]
    frictional = bool(np.any(np.asarray(friction) > 0))
    if normals.shape[0] == 1:
        tangents = tangent_basis(normals[0])[None]
    else:
        tangents = tangent_bases(normals)
    directions = np.concatenate([-normals[:, None, :]] + ([tangents] if frictional else []), axis=1)
    directions = np.where(np.abs(directions) > 1e-12, directions, 0.0)  # round-off of the normal
    directions = np.broadcast_to(directions, (nodes.size,) + directions.shape[1:])  # (n_c, n_dir, dim)
    where = np.full(n_dof, -1)
    where[free] = np.arange(free.size)
    sides = [(nodes, 1.0)] + ([] if others is None else [(others, -1.0)])
    cols = [where[n[:, None] * dim + np.arange(dim)] for n, _ in sides]  # (n_c, dim) each
    movable = np.any([np.any((c >= 0) & (directions[:, 0] != 0), axis=1) for c in cols], axis=0)
    friction = friction if np.ndim(friction) == 0 else np.asarray(friction, float)[movable]
    nodes, g0, directions = nodes[movable], g0[movable], directions[movable]
    cols = [c[movable] for c in cols]
    n_c, n_dir = nodes.size, directions.shape[1]
    # row of (node i, direction k): the normal rows first, then the tangents node by node
    i, k, j = np.meshgrid(np.arange(n_c), np.arange(n_dir), np.arange(dim), indexing="ij")
    row = np.where(k == 0, i, n_c + i * (n_dir - 1) + k - 1)
    triplets = [((sign * directions[i, k, j]).ravel(), c[i, j].ravel()) for (_, sign), c in zip(sides, cols)]
    val, col = (np.concatenate(a) for a in zip(*triplets))
    row = np.tile(row.ravel(), len(sides))
    keep = (col >= 0) & (val != 0)
    if n_c == 0:
        raise ValueError("no node of the face can move towards the wall")
    H = sp.csr_matrix((val[keep], (row[keep], col[keep])), shape=(n_c * n_dir, free.size))
    return WallRows(H, g0, nodes, friction, tol, None if others is None else others[movable])


def _same(a: ContactState, b: ContactState) -> bool:
    return np.array_equal(a.state, b.state) and np.abs(a.direction - b.direction).max(initial=0.0) <= DIRECTION_TOL
