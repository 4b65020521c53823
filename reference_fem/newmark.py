"""Newmark time stepping (alpha = 0.25, delta = 0.5) as a generator over steps.

alpha and delta come from :mod:`cases.timeint` (the convention every solver follows); the
constants are computed here, independently of SMFEM's. The load is
a Heaviside step, on at t = 0, so ``Q(t) = Q`` for every t >= 0 and the initial acceleration
solves ``M a0 = Q - K u0``. (A test scene may pass a load history ``Q(t)`` instead.)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator

import numpy as np

from cases.timeint import ALPHA, DELTA

from .linalg import solve_mass


@dataclass(frozen=True)
class Newmark:
    """Newmark integration constants for one time step ``dt``."""

    dt: float
    a0: float
    a2: float
    a3: float
    a6: float
    a7: float


def newmark_constants(dt: float, alpha: float = ALPHA, delta: float = DELTA) -> Newmark:
    """``a0 = 1/(alpha dt^2)``, ``a2 = 1/(alpha dt)``, ``a3 = 1/(2 alpha) - 1``,
    ``a6 = dt (1 - delta)``, ``a7 = delta dt``."""
    return Newmark(dt, a0=1.0 / (alpha * dt * dt), a2=1.0 / (alpha * dt), a3=0.5 / alpha - 1.0,
                   a6=dt * (1.0 - delta), a7=delta * dt)


def march(system, Q, u0: np.ndarray, v0: np.ndarray, dt: float, n_steps: int,
          ) -> Iterator[tuple[int, float, np.ndarray, np.ndarray, np.ndarray, int]]:
    """Yield ``(step, t, u, v, a, iterations)`` for steps 1 .. ``n_steps``.

    Parameters
    ----------
    system : :class:`~reference_fem.equilibrium.Elastic` (or ``Plastic``) built with
        ``c = a0 = 1 / (alpha dt^2)``; its ``solve(rhs, u)`` returns ``(u, iterations)``
    Q : (n_free,) load vector (N), or a callable ``Q(t)`` returning one
    u0, v0 : (n_free,) initial displacement (m; zero stress assumed, so ``u0`` must be 0
        unless the body is free of stress there) and velocity (m/s)
    dt : time step (s)
    n_steps : number of steps

    Raises
    ------
    reference_fem.equilibrium.NotConverged
        from ``system.solve``; the steps yielded before it stand.
    """
    c = newmark_constants(dt)
    if not np.isclose(system.c, c.a0):
        raise ValueError("system was not built with c = a0 of this time step")
    load = Q if callable(Q) else (lambda t: Q)
    u, v = u0.copy(), v0.copy()
    r0 = load(0.0) - system.A @ u0 + system.c * (system.M @ u0)
    # no force, no acceleration: and massless contact nodes (a singular M) need no solve then
    a = initial_acceleration(system.M, r0) if np.any(r0) else np.zeros_like(u0)
    for n in range(1, n_steps + 1):
        u_new, iterations = system.solve(load(n * dt) + system.M @ (c.a0 * u + c.a2 * v + c.a3 * a), u)
        a_new = c.a0 * (u_new - u) - c.a2 * v - c.a3 * a
        v = v + c.a6 * a + c.a7 * a_new
        u, a = u_new, a_new
        yield n, n * dt, u, v, a, iterations


def initial_acceleration(M, r0: np.ndarray) -> np.ndarray:
    """``M a0 = r0``; the dofs without mass (a contact face's nodes, :mod:`reference_fem.mass`),
    which follow the body quasi-statically, get none (their first step puts them in place)."""
    massive = M.diagonal() > 0
    if massive.all():
        return solve_mass(M, r0)
    on = np.flatnonzero(massive)
    a = np.zeros_like(r0)
    a[on] = solve_mass(M[on][:, on], r0[on])
    return a
