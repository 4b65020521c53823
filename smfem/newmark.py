"""Newmark time stepping of decoupled amplitude subsystems (paper (9)-(11)).

All modes are stepped together as one block-diagonal system: one factorization of
``K + a0 M`` per time-step size, one solve per step, so the per-step overhead stays small
even for many small harmonic blocks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from cases.timeint import newmark_constants


@dataclass
class State:
    """Displacement, velocity and acceleration (reduced, all modes stacked) after step ``n``."""

    n: int
    u: np.ndarray
    v: np.ndarray
    a: np.ndarray


class LinearNewmark:
    """Average-acceleration Newmark for ``M a + K u = Q``.

    Parameters
    ----------
    K : (n, n) sparse stiffness
    M : (n,) lumped mass diagonal, or (n, n) sparse mass where harmonics couple through rho(lm)
    Q : (n,) load held from t = 0
    dt : time step, s
    """

    def __init__(self, K: sp.spmatrix, M, Q: np.ndarray, dt: float):
        self.K, self.Q = K.tocsr(), Q
        self.c = newmark_constants(dt)
        self.diagonal_mass = isinstance(M, np.ndarray) and M.ndim == 1
        self.M = M if self.diagonal_mass else sp.csr_matrix(M)
        self.a0M = self.c.a0 * self.M
        self.lu = sla.splu((self.K + (sp.diags(self.a0M) if self.diagonal_mass else self.a0M)).tocsc())
        self.factorizations = 1
        # a0 u + a2 v + a3 a = a0 (u + b1 v + b2 a): the same right-hand side in fewer operations
        self.b1, self.b2 = self.c.a2 / self.c.a0, self.c.a3 / self.c.a0

    def initial(self, u0: np.ndarray, v0: np.ndarray) -> State:
        """State at t = 0 with ``M a0 = Q - K u0`` (the load is on at t = 0)."""
        force = self.Q - self.K @ u0
        a = force / self.M if self.diagonal_mass else sla.spsolve(self.M.tocsc(), force)
        return State(0, u0.copy(), v0.copy(), a)

    def step(self, s: State) -> State:
        """One step of (9)-(11): ``(K + a0 M) u = Q + M (a0 u + a2 v + a3 a)`` and the updates."""
        c = self.c
        predicted = s.u + self.b1 * s.v + self.b2 * s.a
        u = self.lu.solve(self.Q + (self.a0M * predicted if self.diagonal_mass else self.a0M @ predicted))
        a = c.a0 * (u - predicted)  # = a0 (u - u_t) - a2 v - a3 a
        return State(s.n + 1, u, s.v + c.a6 * s.a + c.a7 * a, a)

    def run(self, state: State, n_steps: int):
        """Yield the state after each of ``n_steps`` steps."""
        for _ in range(n_steps):
            state = self.step(state)
            yield state

    def energy(self, s: State) -> tuple[float, float]:
        """Kinetic and strain energy ``(v'Mv/2, u'Ku/2)``."""
        Mv = self.M * s.v if self.diagonal_mass else self.M @ s.v
        return 0.5 * s.v @ Mv, 0.5 * s.u @ (self.K @ s.u)
