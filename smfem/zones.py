"""Plastic-zone snapshots of an SMFEM run (:class:`cases.result.ZoneSnapshot`): cells in the
plotting plane and their equivalent plastic strain."""

from __future__ import annotations

import math

import numpy as np

from cases.result import ZoneSnapshot

from .inhomogeneity import element_factor


def smfem_snapshot(t: float, model, case, peps: np.ndarray, x3: np.ndarray) -> ZoneSnapshot:
    """Snapshot of SMFEM's ``peps`` (elements, section points, the x3 points ``x3``): per cell
    the element mean (a zone area that converges with the mesh), and ``peak``, the largest
    point value (the quantity of the ``peps_max`` probe, past 0.1 % before any mean is).

    Each element is drawn once per x3 quadrature point as the x3 slice around that point, with
    ``solid`` False in a cut-out; an axisymmetric section shows the largest value along x3
    (they are all equal).
    """
    X, value, peak = model.mesh.element_x(), peps.mean(axis=1), float(peps.max())  # (ne, nodes, 2), (ne, nq)
    if case.body == "ring" and case.axisymmetric:
        return ZoneSnapshot(t, X, value.max(axis=1), peak, np.ones(len(X), bool))
    solid = element_factor(case, model.mesh, x3) == 1.0  # (ne, nq)
    lo1, hi1 = X[:, :, 0].min(1), X[:, :, 0].max(1)
    lo2, hi2 = X[:, :, 1].min(1), X[:, :, 1].max(1)
    period = 2 * math.pi if case.body == "ring" else case.length
    mid = 0.5 * (x3[1:] + x3[:-1])
    edges = np.concatenate([[0.0], mid, [period]])
    a, b = edges[:-1], edges[1:]
    if case.body == "ring":  # a plane section: wedges in x-y
        r0, r1 = lo1[:, None], hi1[:, None]
        ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
        poly = np.stack([np.stack([r0 * ca, r0 * sa], -1), np.stack([r1 * ca, r1 * sa], -1),
                         np.stack([r1 * cb, r1 * sb], -1), np.stack([r0 * cb, r0 * sb], -1)], axis=2)
    else:  # span x height
        A, B = np.broadcast_to(a, (len(X), len(a))), np.broadcast_to(b, (len(X), len(b)))
        z0, z1 = np.broadcast_to(lo2[:, None], A.shape), np.broadcast_to(hi2[:, None], A.shape)
        poly = np.stack([np.stack([A, z0], -1), np.stack([B, z0], -1), np.stack([B, z1], -1),
                         np.stack([A, z1], -1)], axis=2)
    return ZoneSnapshot(t, poly.reshape(-1, 4, 2), value.ravel(), peak, solid.ravel())
