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
    """Average-acceleration Newmark for ``M a + K u = Q`` with diagonal ``M``.

    Parameters
    ----------
    K : (n, n) sparse stiffness; M : (n,) lumped mass diagonal; Q : (n,) load held from t = 0
    dt : time step, s
    """

    def __init__(self, K: sp.spmatrix, M: np.ndarray, Q: np.ndarray, dt: float):
        self.K, self.M, self.Q = K.tocsr(), M, Q
        self.c = newmark_constants(dt)
        self.lu = sla.splu((self.K + sp.diags(self.c.a0 * M)).tocsc())
        self.factorizations = 1

    def initial(self, u0: np.ndarray, v0: np.ndarray) -> State:
        """State at t = 0 with ``M a0 = Q - K u0`` (the load is on at t = 0)."""
        return State(0, u0.copy(), v0.copy(), (self.Q - self.K @ u0) / self.M)

    def step(self, s: State) -> State:
        c = self.c
        u = self.lu.solve(self.Q + self.M * (c.a0 * s.u + c.a2 * s.v + c.a3 * s.a))
        a = c.a0 * (u - s.u) - c.a2 * s.v - c.a3 * s.a
        return State(s.n + 1, u, s.v + c.a6 * s.a + c.a7 * a, a)

    def run(self, state: State, n_steps: int):
        """Yield the state after each of ``n_steps`` steps."""
        for _ in range(n_steps):
            state = self.step(state)
            yield state

    def energy(self, s: State) -> tuple[float, float]:
        """Kinetic and strain energy ``(v'Mv/2, u'Ku/2)``."""
        return 0.5 * s.v @ (self.M * s.v), 0.5 * s.u @ (self.K @ s.u)
