"""An elastic body against the case's rigid wall: the equilibrium system of a contact step (and
of a step with contact pairs between bodies, on their rows: :mod:`reference_fem.pairs`)."""

from __future__ import annotations

import functools

import numpy as np

from cases.params import UnsupportedCase

from .contact import WallContact, WallRows, wall_rows
from .equilibrium import Elastic
from .face import plane_face
from .frames import AXISYMMETRIC

#: penetration tolerance relative to the largest mesh coordinate (round-off level)
PENETRATION_TOL = 1e-12


class WallSystem(Elastic):
    """``(K + c M) u = rhs + H^T p`` with the wall's contact forces ``p`` (:mod:`.contact`).

    ``K + c M`` is factorized once; each step costs one back-substitution, the small dense
    contact problem of its active-set iterations and one product ``W p``.

    Attributes
    ----------
    rows : :class:`~reference_fem.contact.WallRows`
    contact : :class:`~reference_fem.contact.WallContact`
    state : :class:`~reference_fem.contact.ContactState` of the last step
    """

    def __init__(self, model, c: float, rows: WallRows):
        super().__init__(model, c)
        self.rows = rows
        self.contact = WallContact(self.lu, rows)
        self.state = self.contact.initial()

    def solve(self, rhs: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, int]:
        """Solution and active-set iteration count; ``u`` (start of the step) anchors stick."""
        u_star = self.lu.solve(rhs)
        H = self.rows.H
        self.state, its = self.contact.solve(H @ u_star, H @ u, self.state)
        u = u_star + self.contact.W @ self.state.p
        self._elastic_solution(u)
        return u, its


def case_wall_rows(model) -> WallRows:
    """Constraint rows of the face ``case.wall.edge`` of ``model`` against the case's wall."""
    wall = model.case.wall
    if model.case.material.plastic:
        raise UnsupportedCase("reference solver: contact with plasticity is not available")
    if wall.slope and model.rep == AXISYMMETRIC:
        raise UnsupportedCase("reference solver: a tilted wall (wall_slope > 0) is not axisymmetric: use dim=3")
    face = plane_face(model, wall.edge)
    return wall_rows(face.nodes, face.normal, initial_gaps(model, face, face.nodes), model.free,
                     model.basis.N, wall.friction, PENETRATION_TOL * np.abs(model.rmesh.mesh.p).max())


def initial_gaps(model, face, nodes: np.ndarray) -> np.ndarray:
    """The wall's initial gap at mesh ``nodes`` (a tilted wall's grows away from its first-struck
    rim point: :class:`cases.geometry.Wall`); the wall's ``face`` gives the rim's position."""
    x = model.nodes_x[0]  # first Cartesian coordinate (3D) or radius (axisymmetric)
    return model.case.wall.gap_at(x[nodes], x[face.nodes].max())


class ContactLog:
    """Per-step diagnostics of a contact run, for ``ReferenceResult.info``.

    Energies are kinetic plus strain energy ``(v M v + u K u) / 2`` of the whole body (J;
    axisymmetric values are per radian times 2 pi), at t = 0 and at the last step, computed from
    those two states only: at every step, their products with K and M took 4 of the 3D rod's
    27 CPU s. (:class:`reference_fem.pairs.PairLog`: the same of a scene with contact pairs.)
    """

    def __init__(self, system: WallSystem, per_radian: bool):
        self.system = system
        self.factor = 2 * np.pi if per_radian else 1.0
        self.first = self.last = None  # (u, v) on the free dofs, at t = 0 and at the last step
        self.contact_times = []
        self.max_penetration = 0.0

    @functools.cached_property
    def face(self):
        """The wall's face (:func:`~reference_fem.face.plane_face`)."""
        model = self.system.model
        return plane_face(model, model.case.wall.edge)

    @functools.cached_property
    def gap(self) -> np.ndarray:
        """The wall's initial gap at every node."""
        model = self.system.model
        return initial_gaps(model, self.face, np.arange(model.nodes_x.shape[1]))

    def record(self, t: float, u: np.ndarray, v: np.ndarray, u_full: np.ndarray) -> None:
        """Log the state ``u``, ``v`` (free dofs; ``u_full`` all dofs) at time ``t``."""
        s = self.system
        self.last = (u.copy(), v.copy())
        if self.first is None:
            self.first = self.last
        if s.state.p[: s.rows.n_c].sum() > 0:
            self.contact_times.append(t)
        self.max_penetration = max(self.max_penetration, -self.clearance(u_full))

    def clearance(self, u_full: np.ndarray) -> float:
        """Smallest distance of any mesh node to the wall (m), negative when it penetrates."""
        model = self.system.model
        x = model.nodes_x + model.nodal_displacement(u_full)
        return float((self.face.offset + self.gap - self.face.normal @ x).min())

    def energy(self, u: np.ndarray, v: np.ndarray) -> float:
        """Kinetic plus strain energy of the state ``u``, ``v`` (J)."""
        s = self.system
        # elementwise products, not BLAS dot: its threads stall on a busy machine
        return 0.5 * self.factor * float(np.sum(v * (s.M @ v)) + np.sum(u * (s.K @ u)))

    def info(self) -> dict:
        window = [self.contact_times[0], self.contact_times[-1]] if self.contact_times else None
        return {
            "contact_nodes": int(self.system.rows.n_c),
            "energy_before": self.energy(*self.first),
            "energy_after": self.energy(*self.last),
            "contact_window": window,
            "max_penetration": float(self.max_penetration),
        }
