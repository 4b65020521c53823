"""The time-integration convention shared by every solver (CASES.md, common conventions).

Newmark's method with alpha = 0.25, delta = 0.5 (average acceleration), in the notation of the
paper's (9)-(11); the initial acceleration solves ``M a0 = Q(0) - K u0``.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Newmark:
    """Newmark integration constants for one time step ``dt``."""

    dt: float
    alpha: float
    delta: float
    a0: float
    a2: float
    a3: float
    a6: float
    a7: float


def newmark_constants(dt: float, alpha: float = 0.25, delta: float = 0.5) -> Newmark:
    """Constants ``a0 = 1/(alpha dt^2)``, ``a2 = 1/(alpha dt)``, ``a3 = 1/(2 alpha) - 1``,
    ``a6 = dt (1 - delta)``, ``a7 = delta dt``."""
    return Newmark(
        dt, alpha, delta,
        a0=1.0 / (alpha * dt * dt), a2=1.0 / (alpha * dt), a3=0.5 / alpha - 1.0,
        a6=dt * (1.0 - delta), a7=delta * dt,
    )
