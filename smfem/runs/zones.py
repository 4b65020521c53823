"""Plastic-zone snapshots (:class:`cases.result.ZoneSnapshot`, which ``smfem.zones`` and
``reference_fem.zones`` make) on disk, and their areas, for either solver."""

from __future__ import annotations

import numpy as np

from cases.result import ZONE_THRESHOLD as THRESHOLD
from cases.result import ZoneSnapshot


def plastic_area(snapshot: ZoneSnapshot, threshold: float = THRESHOLD) -> float:
    """Area of the solid cells whose peps reaches ``threshold`` (plotting-plane units squared)."""
    poly = snapshot.poly[(snapshot.peps >= threshold) & snapshot.solid_cells]
    x, y = poly[..., 0], poly[..., 1]
    return float(0.5 * np.abs((x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y).sum(axis=1)).sum())


def save(snapshots: list[ZoneSnapshot], path) -> None:
    """Snapshots as one ``.npz`` (``t``, ``peak``, and ``poly_k``/``peps_k``/``solid_k`` per snapshot k)."""
    arrays = {"t": np.array([s.t for s in snapshots]), "peak": np.array([s.peak for s in snapshots])}
    for k, s in enumerate(snapshots):
        arrays[f"poly_{k}"], arrays[f"peps_{k}"] = s.poly, s.peps
        if s.solid is not None:
            arrays[f"solid_{k}"] = s.solid
    np.savez_compressed(path, **arrays)


def load(path) -> list[ZoneSnapshot]:
    """Snapshots written by :func:`save`."""
    with np.load(path) as z:
        return [ZoneSnapshot(float(t), z[f"poly_{k}"], z[f"peps_{k}"], float(z["peak"][k]),
                             z[f"solid_{k}"] if f"solid_{k}" in z else None) for k, t in enumerate(z["t"])]
