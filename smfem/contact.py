"""Contact layer (paper (17)-(19)): thin special elements between a face and a rigid wall.

One layer element sits on every segment of the face ``case.wall.edge``; its far face is the
wall (fixed). The layer is built with the same moment-scheme formulas as any element; only its
elasticity ``D`` depends on the element's state, re-evaluated inside the iterations of a step:

* open (the layer would carry normal tension): ``D = 0``;
* stick: normal stiffness ``E_l`` and tangential stiffness ``G_l = E_l / 2``;
* slip: the tangential row is condensed onto the normal one, ``tau = -f sigma_n * sign``, so
  the tangential stress follows Coulomb's law (18)-(19); with ``f = 0`` a closed element always
  slips.

Only the traction rows of the layer (normal strain, in-plane shear) carry stress: the layer's
own membrane stiffness would otherwise add a spurious tangential restraint.

The initial gap ``g`` enters as a normal pre-strain ``g / h``: the layer closes when the face
has moved ``g`` towards the wall. A layer compressed beyond its thickness (the face went
through the wall) and states that cycle without settling are errors, never silent.

The layer is axisymmetric (harmonic 0, cosine family: radial and axial motion), as the paper's
rod impact; other scenes raise :class:`~smfem.model.ModelError`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from cases.timeint import newmark_constants

from . import assembly, element, fourier
from .model import ModelError

OPEN, STICK, SLIP_POS, SLIP_NEG = 0, 1, 2, 3
NORMAL, SHEAR = 1, 3  # strain rows e22 (normal to the layer) and g12 (in-plane tangential)
#: iterations over the layer states allowed in one step
MAX_STATE_ITERATIONS = 30


class ContactError(RuntimeError):
    """Contact states that do not settle, or a face pushed through the wall."""


class ContactLayer:
    """Layer elements on ``case.wall.edge`` of a harmonic-0 model.

    Parameters
    ----------
    model : :class:`smfem.model.Model` of an axisymmetric ring (mode 0, cosine family only)
    thickness : layer thickness h (length units of the case)
    stiffness : layer Young's modulus E_l
    """

    def __init__(self, model, thickness: float, stiffness: float):
        case = model.case
        if [str(m) for m in model.modes] != [str(fourier.Mode(0, "c"))] or len(model.systems) != 1:
            raise ModelError(f"{case.name}: the contact layer is implemented for axisymmetric scenes "
                             f"(harmonic 0, radial and axial motion) only")
        self.model, self.h, self.E = model, float(thickness), float(stiffness)
        self.gap, self.f = float(case.wall.gap), float(case.wall.friction)
        mesh = model.mesh
        face = mesh.edge_nodes(case.wall.edge)
        seg, owner = mesh.edge_segments(case.wall.edge)
        x = mesh.x
        tangent = x[seg[:, 1]] - x[seg[:, 0]]
        normal = np.column_stack([tangent[:, 1], -tangent[:, 0]])
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        inward = mesh.element_x()[owner].mean(axis=1) - 0.5 * (x[seg[:, 0]] + x[seg[:, 1]])
        normal *= -np.sign(np.einsum("ea,ea->e", normal, inward))[:, None]  # outward, towards the wall
        out_node = np.zeros((len(face), 2))
        np.add.at(out_node, seg, normal[:, None, :])
        out_node /= np.linalg.norm(out_node, axis=1, keepdims=True)
        wall = x[face] + self.h * out_node
        where = {n: k for k, n in enumerate(face)}
        a, b = np.array([where[n] for n in seg[:, 0]]), np.array([where[n] for n in seg[:, 1]])
        X = np.stack([wall[a], wall[b], x[seg[:, 1]], x[seg[:, 0]]], axis=1)  # xi along the face
        self.ops = element.operators(X, case.body, 0.0)
        self.face_nodes = seg[:, ::-1]  # local nodes 2, 3 of each layer element
        self.dofs = (3 * self.face_nodes[:, :, None] + np.arange(3)).reshape(len(seg), 6)
        self.area = self.ops.sqrt_g.copy()  # per radian of circumference, as the model's integrals
        mode = model.modes[0]
        i1, i3 = fourier.psi_squared_integrals(mode, model.body, model.length)
        self.integrals = np.zeros((len(seg), 2, 2))
        self.integrals[:, 0, 0], self.integrals[:, 1, 1] = i1, i3
        self.T = model.systems[0].T
        B0 = self.ops.at(0.0)[0]
        self.B_face = B0[:, :, 6:]  # centre strain from the face nodes (the wall does not move)
        self.slip_strain = np.zeros(len(seg))  # committed tangential slip (strain) per element
        n = len(seg)
        self.state = np.full(n, OPEN)

    # -- constitutive state -------------------------------------------------------------------
    def centre_strain(self, u_full: np.ndarray) -> np.ndarray:
        """(n, 6) layer strain at the element centres of a full displacement vector."""
        return np.einsum("erk,ek->er", self.B_face, u_full[self.dofs])

    def states_of(self, strain: np.ndarray) -> np.ndarray:
        """State of every layer element for a strain (the committed slip taken into account)."""
        closure = strain[:, NORMAL] + self.gap / self.h
        sigma_n = self.E * closure
        tau = 0.5 * self.E * (strain[:, SHEAR] - self.slip_strain)
        state = np.where(tau >= 0, SLIP_POS, SLIP_NEG)
        state = np.where((self.f > 0) & (np.abs(tau) <= self.f * np.abs(sigma_n)), STICK, state)
        return np.where(closure >= 0, OPEN, state)

    def D(self, state: np.ndarray) -> np.ndarray:
        """(n, 6, 6) layer elasticity of each element's state."""
        D = np.zeros((len(state), 6, 6))
        closed = state != OPEN
        D[closed, NORMAL, NORMAL] = self.E
        D[state == STICK, SHEAR, SHEAR] = 0.5 * self.E
        sign = np.where(state == SLIP_POS, 1.0, np.where(state == SLIP_NEG, -1.0, 0.0))
        D[:, SHEAR, NORMAL] = -self.f * self.E * sign  # tau = -f sigma_n sign: (18)-(19)
        return D

    def offset_strain(self, state: np.ndarray) -> np.ndarray:
        """(n, 6) strain the layer adds to the displacement's: the gap and the committed slip."""
        e = np.zeros((len(state), 6))
        e[:, NORMAL] = self.gap / self.h
        e[:, SHEAR] = np.where(state == STICK, -self.slip_strain, 0.0)
        return e

    def stress(self, strain: np.ndarray, state: np.ndarray) -> np.ndarray:
        return np.einsum("ers,es->er", self.D(state), strain + self.offset_strain(state))

    # -- matrices and forces (reduced dofs of mode 0) -----------------------------------------
    def stiffness(self, state: np.ndarray) -> sp.csr_matrix:
        blocks = element.element_stiffness(self.ops, 0.0, assembly.weighted_elasticity(self.D(state), self.integrals))
        n_full = 3 * self.model.mesh.n_nodes
        face = blocks[:, 6:, 6:]
        rows = np.repeat(self.dofs, 6, axis=1).ravel()
        cols = np.tile(self.dofs, (1, 6)).ravel()
        K = sp.csr_matrix((face.ravel(), (rows, cols)), shape=(n_full, n_full))
        return (self.T.T @ K @ self.T).tocsr()

    def offset_force(self, state: np.ndarray) -> np.ndarray:
        """Reduced nodal forces of the offset strain, ``int B' D e_off``."""
        Dw = assembly.weighted_elasticity(self.D(state), self.integrals)
        per = np.einsum("erk,ers,es,e->ek", self.B_face, Dw, self.offset_strain(state), self.ops.sqrt_g)
        full = np.bincount(self.dofs.ravel(), per.ravel(), minlength=3 * self.model.mesh.n_nodes)
        return self.T.T @ full

    def commit(self, strain: np.ndarray, state: np.ndarray) -> None:
        """End of a converged step: slipping elements carry their slip; the states become the
        next step's first guess."""
        sigma = self.stress(strain, state)
        slipping = (state == SLIP_POS) | (state == SLIP_NEG)
        self.slip_strain = np.where(slipping, strain[:, SHEAR] - sigma[:, SHEAR] / (0.5 * self.E), self.slip_strain)
        self.slip_strain = np.where(state == OPEN, strain[:, SHEAR], self.slip_strain)
        self.state = state

    def mean_normal_stress(self, strain: np.ndarray, state: np.ndarray) -> float:
        """Mean normal stress on the face (compressive negative): the contact pressure."""
        return float(self.area @ self.stress(strain, state)[:, NORMAL] / self.area.sum())


def face_free_mass(model, edge: str) -> np.ndarray:
    """Lumped mass (3 n_nodes,) with the face nodes' mass moved to the next row inside.

    A massive face node on the stiff layer is an oscillator far above what dt resolves:
    Newmark leaves it undamped and the contact pressure rings at the Nyquist frequency. With
    massless contact nodes (mass redistribution, Khenous, Laborde & Renard 2008) the face
    follows quasi-statically; the total mass is kept.
    """
    m = model.full_mass(0, 0).reshape(-1, 3).copy()
    ns, nt = model.mesh.shape
    grid = np.arange(model.mesh.n_nodes).reshape(nt + 1, ns + 1)
    face, inside = {"s_min": (grid[:, 0], grid[:, 1]), "s_max": (grid[:, -1], grid[:, -2]),
                    "t_min": (grid[0], grid[1]), "t_max": (grid[-1], grid[-2])}[model.mesh.section.edge(edge)]
    m[inside] += m[face]
    m[face] = 0.0
    return m.ravel()


class ContactNewmark:
    """Average-acceleration Newmark of a harmonic-0 model with a contact layer.

    Each step iterates: solve with the layer matrix of the current states, re-evaluate the
    states from the new displacements, until no state changes. ``K + a0 M`` is factorized once:
    the layer touches only the face dofs, so ``(K + a0 M + P' k P) x = b`` is solved as
    ``x = y - Z c`` with ``y = A0^-1 b``, ``Z = A0^-1 P'`` (computed once) and the small dense
    system ``(I + k S) c = k P y``, ``S = P Z`` (Woodbury, with ``k`` the layer's face block).
    """

    def __init__(self, model, layer: ContactLayer, dt: float, massless_face: bool = True):
        s = model.systems[0]
        self.K, self.Q, self.layer = s.K, s.Q, layer
        # massless_face=False keeps the face nodes' mass: only to show what it does (tests)
        self.m_full = face_free_mass(model, model.case.wall.edge) if massless_face else model.full_mass(0, 0)
        self.M = s.T.multiply(s.T).T @ self.m_full
        self.c = newmark_constants(dt)
        self.lu = sla.splu((self.K + sp.diags(self.c.a0 * self.M)).tocsc())
        self.factorizations = 1
        # the reduced dofs any layer state can touch, and the solution's response to them
        every = np.full(len(layer.state), STICK)
        self.face = np.unique(layer.stiffness(every).tocoo().row)
        P = np.zeros((len(self.M), len(self.face)))
        P[self.face, np.arange(len(self.face))] = 1.0
        self.Z = self.lu.solve(P)
        self.S = self.Z[self.face]
        self.face_blocks: dict[bytes, np.ndarray] = {}
        self.max_closure = 0.0  # largest layer compression over the run, in layer thicknesses

    def _solve(self, state: np.ndarray, rhs: np.ndarray) -> np.ndarray:
        y = self.lu.solve(rhs)
        key = state.tobytes()
        if key not in self.face_blocks:  # a few patterns recur over a run
            self.face_blocks[key] = self.layer.stiffness(state)[self.face][:, self.face].toarray()
        k = self.face_blocks[key]
        if not k.any():
            return y
        c = np.linalg.solve(np.eye(len(k)) + k @ self.S, k @ y[self.face])
        return y - self.Z @ c

    def initial_acceleration(self, u: np.ndarray) -> np.ndarray:
        """``M a = Q - K u``; the massless face nodes carry no initial acceleration."""
        force = self.Q - self.K @ u
        return np.divide(force, self.M, out=np.zeros_like(force), where=self.M > 0)

    def step(self, u, v, a, step_index: int, t: float):
        """One step; returns ``(u, v, a, iterations, strain, state)``."""
        c, layer = self.c, self.layer
        predicted = u + (c.a2 / c.a0) * v + (c.a3 / c.a0) * a
        state, seen = layer.state, set()
        for iteration in range(1, MAX_STATE_ITERATIONS + 1):
            seen.add(state.tobytes())
            rhs = self.Q + c.a0 * self.M * predicted - layer.offset_force(state)
            new = self._solve(state, rhs)
            strain = layer.centre_strain(layer.T @ new)
            next_state = layer.states_of(strain)
            if np.array_equal(next_state, state):
                break
            if next_state.tobytes() in seen:
                raise ContactError(f"step {step_index} (t = {t:.6g} s): contact states cycle without settling "
                                   f"after {iteration} iterations (state chattering)")
            state = next_state
        else:
            raise ContactError(f"step {step_index} (t = {t:.6g} s): contact states did not settle in "
                               f"{MAX_STATE_ITERATIONS} iterations")
        closure = -(strain[:, NORMAL] + layer.gap / layer.h)
        self.max_closure = max(self.max_closure, float(closure.max()))
        if closure.max() >= 1.0:
            raise ContactError(f"step {step_index} (t = {t:.6g} s): the face went through the wall (layer "
                               f"compressed {closure.max():.3g} times its thickness): raise layer_stiffness "
                               f"or lower dt")
        layer.commit(strain, state)
        acc = c.a0 * (new - predicted)
        vel = v + c.a6 * a + c.a7 * acc
        return new, vel, acc, iteration, strain, state
