"""Figures a run writes: plastic zones (equivalent plastic strain >= 0.1 %) at chosen times."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

THRESHOLD = 1e-3  # peps that counts as plastic


def _cells(snap):
    """Polygons (n_cells, 4, 2) in the plotting plane and the peps of each cell."""
    X, x3, peps = snap["element_x"], snap["x3"], snap["peps"]  # (ne, 4, 2), (nq,), (ne, nq)
    lo1, hi1 = X[:, :, 0].min(1), X[:, :, 0].max(1)
    lo2, hi2 = X[:, :, 1].min(1), X[:, :, 1].max(1)
    if snap["body"] == "ring" and snap["axisymmetric"]:
        return X, peps.max(axis=1)
    period = 2 * math.pi if snap["body"] == "ring" else snap["length"]
    mid = 0.5 * (x3[1:] + x3[:-1])
    edges = np.concatenate([[0.0], mid, [period]])
    a, b = edges[:-1], edges[1:]
    if snap["body"] == "ring":  # a plane section: wedges in x-y
        r0, r1 = lo1[:, None], hi1[:, None]
        ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
        poly = np.stack([np.stack([r0 * ca, r0 * sa], -1), np.stack([r1 * ca, r1 * sa], -1),
                         np.stack([r1 * cb, r1 * sb], -1), np.stack([r0 * cb, r0 * sb], -1)], axis=2)
    else:  # span x height
        A, B = np.broadcast_to(a, (len(X), len(a))), np.broadcast_to(b, (len(X), len(b)))
        z0, z1 = np.broadcast_to(lo2[:, None], A.shape), np.broadcast_to(hi2[:, None], A.shape)
        poly = np.stack([np.stack([A, z0], -1), np.stack([B, z0], -1), np.stack([B, z1], -1), np.stack([A, z1], -1)], axis=2)
    return poly.reshape(-1, 4, 2), peps.ravel()


def plastic_zones(snapshots: list[dict], path: Path, title: str) -> None:
    """One panel per snapshot; cells with peps >= 0.1 % coloured by peps (in %)."""
    vmax = max([100 * s["peps"].max() for s in snapshots] + [0.2])
    fig, axes = plt.subplots(1, len(snapshots), figsize=(4.2 * len(snapshots), 4.2), squeeze=False)
    for ax, snap in zip(axes[0], snapshots):
        poly, value = _cells(snap)
        outline = PolyCollection(poly, facecolors="none", edgecolors="0.85", linewidths=0.1)
        ax.add_collection(outline)
        hot = value >= THRESHOLD
        cells = PolyCollection(poly[hot], array=100 * value[hot], cmap="inferno_r", clim=(0.1, vmax), edgecolors="none")
        ax.add_collection(cells)
        ax.autoscale()
        ax.set_aspect("equal")
        ax.set_title(f"t = {1e3 * snap['t']:.4g} ms, {int(hot.sum())} plastic cells", fontsize=9)
        ax.tick_params(labelsize=7)
    fig.colorbar(cells, ax=axes[0].tolist(), label="equivalent plastic strain, % (>= 0.1)", shrink=0.8)
    fig.suptitle(title, fontsize=10)
    fig.savefig(path, dpi=130)
    plt.close(fig)
