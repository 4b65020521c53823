"""Figures a run writes: plastic zones (equivalent plastic strain >= 0.1 %) at chosen times."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

THRESHOLD = 1e-3  # peps that counts as plastic


def plastic_zones(rows: dict[str, list[dict]], path: Path, title: str) -> None:
    """One row of panels per solver (label -> snapshots of :mod:`runs.zones`), one panel per
    time; cells with peps >= 0.1 % coloured by peps (in %) on one colour scale for all rows."""
    rows = {label: snaps for label, snaps in rows.items() if snaps}
    vmax = max([100 * s["peps"].max() for snaps in rows.values() for s in snaps] + [0.2])
    ncol = max(len(snaps) for snaps in rows.values())
    fig, axes = plt.subplots(len(rows), ncol, figsize=(4.2 * ncol, 4.0 * len(rows) + 0.4), squeeze=False)
    cells = None
    for axrow, (label, snaps) in zip(axes, rows.items()):
        for ax in axrow[len(snaps):]:
            ax.axis("off")
        for ax, snap in zip(axrow, snaps):
            poly, value = snap["poly"], snap["peps"]
            ax.add_collection(PolyCollection(poly, facecolors="none", edgecolors="0.85", linewidths=0.1))
            hot = value >= THRESHOLD
            cells = PolyCollection(poly[hot], array=100 * value[hot], cmap="inferno_r", clim=(0.1, vmax),
                                   edgecolors="none")
            ax.add_collection(cells)
            ax.autoscale()
            ax.set_aspect("equal")
            ax.set_title(f"{label}: t = {1e3 * snap['t']:.4g} ms, {int(hot.sum())} plastic cells", fontsize=9)
            ax.tick_params(labelsize=7)
    fig.colorbar(cells, ax=axes.ravel().tolist(), label="equivalent plastic strain, % (>= 0.1)", shrink=0.8)
    fig.suptitle(title, fontsize=10)
    fig.savefig(path, dpi=130)
    plt.close(fig)
