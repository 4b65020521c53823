"""Plastic-zone snapshots on disk and their areas, for either solver.

A snapshot is ``{"t": time, "poly": (n, 4, 2) cell corners, "peps": (n,) cell means, "peak":
the largest point value}`` (``peak`` is what the ``peps_max`` probe gives; a cell's mean stays
below it), and where the mesh covers cut-outs (SMFEM's fictitious material) ``"solid": (n,)``
bool, in
the plane both solvers draw in: the x-y plane of a ring, the (r, z) half-plane of an
axisymmetric ring, the (span, height) plane of a prism (``smfem.zones`` and
``reference_fem.zones`` make them).
"""

from __future__ import annotations

import numpy as np

#: the equivalent plastic strain that counts as plastic
THRESHOLD = 1e-3


def plastic_area(snapshot: dict, threshold: float = THRESHOLD) -> float:
    """Area of the solid cells whose peps reaches ``threshold`` (plotting-plane units squared)."""
    hot = snapshot["peps"] >= threshold
    if "solid" in snapshot:
        hot &= snapshot["solid"]
    poly = snapshot["poly"][hot]
    x, y = poly[..., 0], poly[..., 1]
    return float(0.5 * np.abs((x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y).sum(axis=1)).sum())


def save(snapshots: list[dict], path) -> None:
    """Snapshots as one ``.npz`` (``t``, ``peak``, and ``poly_k``/``peps_k``/``solid_k`` per snapshot k)."""
    arrays = {"t": np.array([s["t"] for s in snapshots]), "peak": np.array([s["peak"] for s in snapshots])}
    for k, s in enumerate(snapshots):
        arrays[f"poly_{k}"], arrays[f"peps_{k}"] = s["poly"], s["peps"]
        if "solid" in s:
            arrays[f"solid_{k}"] = s["solid"]
    np.savez_compressed(path, **arrays)


def load(path) -> list[dict]:
    """Snapshots written by :func:`save`."""
    with np.load(path) as z:
        return [{"t": float(t), "poly": z[f"poly_{k}"], "peps": z[f"peps_{k}"], "peak": float(z["peak"][k]),
                 **({"solid": z[f"solid_{k}"]} if f"solid_{k}" in z else {})} for k, t in enumerate(z["t"])]
