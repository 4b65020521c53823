"""Plastic-zone snapshots of a 2D reference run, in the format of ``runs.zones``.

``{"t", "poly": (n, 4, 2) corner points, "peps": (n,) element means, "peak": the largest point
value}`` in the mesh plane, which is the plane SMFEM draws in (ring: x-y; axisymmetric: r-z;
prism: span-height).
"""

from __future__ import annotations

import numpy as np


def snapshot(t: float, model, system) -> dict:
    """Snapshot of the equivalent plastic strain of a 2D model: element means, and the largest
    point value (the quantity of the ``peps_max`` probe)."""
    mesh = model.rmesh.mesh
    poly = mesh.p[:, mesh.t[:4]].transpose(2, 1, 0)  # corners of the curved quads
    return {"t": t, "poly": poly, "peps": system.peps.reshape(mesh.nelements, -1).mean(axis=1),
            "peak": float(system.peps.max())}
