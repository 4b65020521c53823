"""Isotropic elasticity in the strain order ``[e11, e22, e33, g12, g13, g23]`` (engineering shears)."""

from __future__ import annotations

import numpy as np

from cases.material import lame


def isotropic_D(E: float, nu: float) -> np.ndarray:
    """(6, 6) elasticity matrix."""
    lam, mu = lame(E, nu)
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[[0, 1, 2], [0, 1, 2]] += 2 * mu
    D[[3, 4, 5], [3, 4, 5]] = mu
    return D
