"""The error against a known exact motion (``Case.exact``): the relative L2 norm over the body.

Code verification's global measure, with the reference's own quadratic shape functions and
quadrature: the displacement interpolated at the quadrature points, turned into body
components, against the exact field there. A global norm converges at the element's order (3
for the quadratic element) on any mesh; a node's value may superconverge before it does.
"""

from __future__ import annotations

import numpy as np

from cases.manufactured import numeric, time_function

from .frames import body_coordinates, body_rotation


def error_l2(model, u_full: np.ndarray, motion, t: float) -> float | None:
    """``||u_h - u|| / ||u||`` at time ``t`` of the full displacement vector ``u_full``; None
    where the model leaves out a direction the motion varies along (a 2D model)."""
    x_qp = model.x_qp
    x1, x2, x3 = body_coordinates(model.case, model.rep, x_qp)
    exact = np.array([np.asarray(numeric(c)(x1, x2, x3, 0.0), float) for c in motion.pattern])
    if not np.isfinite(exact).all():
        return None
    exact *= time_function(motion.time)(t)
    u_mesh = np.asarray(model.basis.interpolate(u_full)).reshape(model.dim, -1)
    u_mesh = np.vstack([u_mesh, np.zeros((3 - model.dim, u_mesh.shape[1]))])
    u_body = np.einsum("nij,jn->in", body_rotation(model.case, model.rep, x_qp), u_mesh)
    w = model.weights
    return float(np.sqrt((w * ((u_body - exact) ** 2).sum(0)).sum() / (w * (exact**2).sum(0)).sum()))
