"""The error against a known exact motion (``Case.exact``): the relative L2 norm over the body.

Code verification's global measure: the displacement the amplitudes synthesize, with the
element's shape functions, against the exact field, integrated by the section quadrature the
force terms use (:func:`smfem.loads.section_points`, 3 x 3 Gauss points per element) and along x3 by Gauss-Legendre (prism) or the trapezoidal rule around the ring
(exact for its harmonics). A global norm converges at the element's order (2) on any mesh;
a single point's value may superconverge before it does.
"""

from __future__ import annotations

import math

import numpy as np

from cases.geometry import RING
from cases.manufactured import numeric, time_function

from . import fourier
from .loads import section_points

X3_POINTS = 64


def error_l2(model, u_modes: list[np.ndarray], motion, t: float) -> float:
    """``||u_h - u|| / ||u||`` at time ``t`` of the amplitudes ``u_modes`` (one per system)."""
    x, area, N, dofs = section_points(model.mesh, model.body, model.element)  # a ring's area times r
    if model.body == RING:
        x3 = np.arange(X3_POINTS) * 2 * math.pi / X3_POINTS
        w3 = np.full(X3_POINTS, 2 * math.pi / X3_POINTS)
    else:
        g3, w3 = np.polynomial.legendre.leggauss(X3_POINTS)
        x3, w3 = (g3 + 1) * model.length / 2, w3 * model.length / 2
    u = np.zeros((len(x3),) + area.shape + (3,))
    for s, amp in zip(model.systems, u_modes):
        nodal = (s.T @ amp).reshape(-1, 3)[dofs]  # (ne, nodes, 3), section axes and x3
        at = np.einsum("gi,eic->egc", N, nodal)
        psi1, psi3 = fourier.psi(s.mode, x3, model.body, model.length)
        u += np.einsum("k,egc->kegc", psi1, at * [1, 1, 0]) + np.einsum("k,egc->kegc", psi3, at * [0, 0, 1])
    shape = u.shape[:-1]
    x1, x2, X3 = (np.broadcast_to(a, shape) for a in (x[None, ..., 0], x[None, ..., 1], x3[:, None, None]))
    g_t = time_function(motion.time)(t)
    exact = np.stack([np.broadcast_to(np.asarray(numeric(c)(x1, x2, X3, 0.0), float), shape) * g_t
                      for c in motion.pattern], axis=-1)
    weight = w3[:, None, None] * area[None]
    return float(np.sqrt((weight * ((u - exact) ** 2).sum(-1)).sum() / (weight * (exact**2).sum(-1)).sum()))
