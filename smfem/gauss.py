"""The 2-stage Gauss-Legendre method for SMFEM's linear runs (``--set time_scheme=gauss``).

Order 4 in dt, A-stable and without numerical damping, against the order 2 of Newmark's
average acceleration (:mod:`smfem.newmark`, the paper's and the default). Of ``M u'' + K u =
f(t)`` written as ``u' = v, M v' = f - K u``, the stage displacements ``U`` (2, n) at
``t + c_i dt`` (``c = 1/2 -+ sqrt 3 / 6``) satisfy, with the method's matrix ``A`` (2, 2),

    (A^-2 (x) M / dt^2) U + (I (x) K) U = F + (A^-2 1 (x) M / dt^2) u + (A^-1 1 (x) M / dt) v,

``F`` (2, n) the load at the stages. ``A^-1`` has the eigenvalues ``mu = 3 +- i sqrt 3``: in its
eigenbasis the two stage equations are one complex system ``(K + mu^2 / dt^2 M) w = r`` and its
conjugate, so a step is one solve with a complex matrix factorized once per run. The step's end
follows from the stages without a mass solve (``d = b' A^-1``, ``d' 1 = 0``):
``u_new = u + d' U``, ``v_new = v + d' A^-1 (U - 1 u) / dt``. The acceleration the states carry,
``M^-1 (f - K u_new)``, costs a product with ``K`` (and a solve with a coupled mass).

Measured on the elastic thick cylinder: 5 to 25 times less time error than Newmark at the
same dt for 1.6 to 3.4 times its CPU per step (benchmarks/time_schemes.py).
"""

from __future__ import annotations

import math
from typing import Iterator

import numpy as np

from .linalg import sparse_lu
from .newmark import LinearSystem, MassSolve, State
from .newmark import march as newmark_march

ROOT3 = math.sqrt(3.0)
#: the stages' times within a step, in steps
NODES = np.array([0.5 - ROOT3 / 6, 0.5 + ROOT3 / 6])
#: the method's Butcher matrix and weights
A = np.array([[0.25, 0.25 - ROOT3 / 6], [0.25 + ROOT3 / 6, 0.25]])
WEIGHTS = np.array([0.5, 0.5])
A_INV = np.linalg.inv(A)
#: an eigenvalue of ``A^-1`` (3 + i sqrt 3), its eigenvector ``T0``, and the row of
#: ``[T0, conj(T0)]^-1`` that maps the stage equations onto its complex system
MU = 3.0 + 1j * ROOT3
T0 = np.array([A_INV[0, 1], MU - A_INV[0, 0]])
TO_COMPLEX = np.linalg.inv(np.column_stack([T0, T0.conj()]))[0]
#: ``d = b' A^-1``: the step's end from the stages
D = WEIGHTS @ A_INV
#: the step's start in the complex system's right-hand side: ``u`` and ``dt v`` times ``M / dt^2``
FROM_U, FROM_V = TO_COMPLEX @ (A_INV @ A_INV).sum(axis=1), TO_COMPLEX @ A_INV.sum(axis=1)


class GaussSystem(LinearSystem):
    """``M a + K u = Q + sum g_k(t) Q_k`` (as :class:`smfem.newmark.LinearSystem`, whose
    parameters it takes) stepped by :func:`march`: one factorization of ``K + mu^2 / dt^2 M``."""

    def factorize(self, dt: float):
        """The complex stage matrix's factorization (and the coupled mass's, for accelerations).

        The matrix is complex symmetric with a positive definite real part (``Re mu^2 > 0``),
        so it is factorized in a symmetric ordering with diagonal pivots, as a real stiffness
        is (:func:`smfem.linalg.sparse_lu`): less than half the fill of SuperLU's default column
        ordering on the flywheel's 9-node harmonics (benchmarks/README.md)."""
        self.mass_solve = MassSolve(self.M)
        return self.step_factors((MU * MU / (dt * dt)) * self.M, sparse_lu)

    def acceleration(self, t: float, u: np.ndarray) -> np.ndarray:
        """``M^-1 (f(t) - K u)``."""
        force = self.load(t) - self.K @ u
        return self.mass_solve(force)

    def initial_acceleration(self, u0: np.ndarray) -> np.ndarray:
        return self.acceleration(0.0, u0)

    def step(self, u: np.ndarray, v: np.ndarray, t: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """``(u, v)`` at ``t + dt`` from ``(u, v)`` at ``t``."""
        stage_loads = TO_COMPLEX @ np.stack([self.load(t + c * dt) for c in NODES])
        w = self.lu.solve(stage_loads + self.mass_times(FROM_U * u + (FROM_V * dt) * v) / (dt * dt))
        stages = 2.0 * np.real(T0[:, None] * w[None, :])  # U = T0 w + conj(T0 w)
        return u + D @ stages, v + (D @ A_INV @ stages - (D @ A_INV).sum() * u) / dt


def march(system: GaussSystem, u0: np.ndarray, v0: np.ndarray, dt: float, n_steps: int) -> Iterator[State]:
    """Yield the state at t = 0, then after each of ``n_steps`` steps (as
    :func:`smfem.newmark.march` does; every step one solve, ``iterations`` 1)."""
    u, v = u0.copy(), v0.copy()
    yield State(0, u, v, system.initial_acceleration(u))
    for n in range(1, n_steps + 1):
        u, v = system.step(u, v, (n - 1) * dt, dt)
        yield State(n, u, v, system.acceleration(n * dt, u), 1)


def march_for(system):
    """How ``system`` marches: :func:`march` for a :class:`GaussSystem`, else Newmark's."""
    return march if isinstance(system, GaussSystem) else newmark_march
