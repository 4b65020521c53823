"""Plastic-zone snapshots of a 2D reference run (:class:`cases.result.ZoneSnapshot`): element
means in the mesh plane, which is the plane SMFEM draws in (ring: x-y; axisymmetric: r-z;
prism: span-height).
"""

from __future__ import annotations


from cases.result import ZoneSnapshot


def snapshot(t: float, model, system) -> ZoneSnapshot:
    """Snapshot of the equivalent plastic strain of a 2D model: element means, and the largest
    point value (the quantity of the ``peps_max`` probe)."""
    mesh = model.rmesh.mesh
    poly = mesh.p[:, mesh.t[:4]].transpose(2, 1, 0)  # corners of the curved quads
    return ZoneSnapshot(t, poly, system.peps.reshape(mesh.nelements, -1).mean(axis=1), float(system.peps.max()))
