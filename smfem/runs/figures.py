"""Figures a run writes (plastic zones at chosen times), and what every figure of the project
goes through: label placement clear of markers and other labels, and a layout check on save.

The check (:func:`layout_problems`) renders the figure and finds text drawn outside it, labels
on top of each other or of a marker, and axes whose quantity has no unit (``"name, unit"``;
``-`` for a dimensionless one). :func:`save` warns with :class:`FigureLayoutWarning` for each;
the tests turn that warning into an error, so every figure a test draws is checked.
"""

from __future__ import annotations

import itertools
import re
import warnings
from pathlib import Path

import matplotlib.image
import matplotlib.patches
import matplotlib.ticker
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from matplotlib.legend import Legend
from matplotlib.text import Annotation, Text

from .zones import THRESHOLD, plastic_area

#: the resolution figures are made, checked and written at, dots per inch
DPI = 120

#: the colour of a cut-out in the plastic-zone figures
CUTOUT = "#b8c7d9"
#: an axis label names its quantity, then its unit after the last comma
UNIT = re.compile(r",\s*\S[^,]*$")


def subplots(nrows: int = 1, ncols: int = 1, *, figsize=None, layout=None, **kwargs):
    """``plt.subplots`` at :data:`DPI` on an Agg canvas of its own, outside pyplot: a figure is
    laid out at the resolution it is written at, and matplotlib's globals (its backend, its
    default dpi, pyplot's figures), which a user of this package keeps, are left alone."""
    fig = Figure(figsize=figsize, dpi=DPI, layout=layout)
    FigureCanvasAgg(fig)
    return fig, fig.subplots(nrows, ncols, **kwargs)


def close(fig) -> None:
    """Let go of a written figure (a pyplot figure, as a test may make, is closed in pyplot)."""
    if fig.canvas.manager is not None:
        import matplotlib.pyplot as plt

        plt.close(fig)


class FigureLayoutWarning(UserWarning):
    """A figure's text is cut off, hidden under another label or a marker, or an axis has no unit."""


def save(fig, path: Path, dpi: int = DPI) -> Path:
    """Check the layout at the resolution written (a warning per problem), write the figure
    (PNG) from the drawing the check made and close it: ``savefig`` would lay the figure out
    and draw it twice more, a third of a figure's CPU time. Figures are made at :data:`DPI`, so
    point labels are placed at the resolution they are checked and written at (placed at
    another, text rendered at the new size touched markers the placement had kept clear of)."""
    fig.set_dpi(dpi)
    if not isinstance(fig.canvas, FigureCanvasAgg):  # drawn off-screen whatever made it
        FigureCanvasAgg(fig)
    for problem in layout_problems(fig):
        warnings.warn(f"{Path(path).name}: {problem}", FigureLayoutWarning, stacklevel=2)
    matplotlib.image.imsave(path, fig.canvas.buffer_rgba(), format="png", origin="upper", dpi=dpi)
    close(fig)
    return path


def _texts(fig) -> list[tuple[str, object, Text | Legend]]:
    """(what, bbox, artist) of every text drawn: the figure's and each axes' titles, axis labels,
    offsets, the tick labels drawn, annotations and texts, and each legend as one box."""
    renderer = fig.canvas.get_renderer()
    artists = list(fig.texts)  # the suptitle among them
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        artists += [ax.title, ax._left_title, ax._right_title, *ax.texts]
        if ax.axison:
            for axis in (ax.xaxis, ax.yaxis):
                if axis.get_visible():
                    artists += [axis.label, axis.get_offset_text()]
                    # the ticks inside the view: the ones drawn
                    artists += [lab for tick in axis._update_ticks() for lab in (tick.label1, tick.label2)]
    out = [(f"text {t.get_text()!r}", t.get_window_extent(renderer), t) for t in artists
           if t.get_visible() and t.get_text().strip()]
    legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes)]
    return out + [("legend", leg.get_window_extent(renderer), leg) for leg in legends
                  if leg is not None and leg.get_visible()]


def _overlap(a, b, slack: float = 1.0) -> bool:
    return (min(a.x1, b.x1) - max(a.x0, b.x0) > slack) and (min(a.y1, b.y1) - max(a.y0, b.y0) > slack)


def _markers(ax) -> np.ndarray:
    """(n, 3) display x, y and radius (px) of the markers drawn in ``ax``."""
    rows = []
    for line in ax.get_lines():
        if not line.get_visible() or line.get_marker() in (None, "None", "none", "", " "):
            continue
        xy = line.get_transform().transform(np.asarray(line.get_xydata(), float))
        xy = xy[np.isfinite(xy).all(axis=1)]
        r = 0.5 * line.get_markersize() * ax.figure.dpi / 72.0
        rows += [(x, y, r) for x, y in xy if ax.bbox.x0 <= x <= ax.bbox.x1 and ax.bbox.y0 <= y <= ax.bbox.y1]
    return np.array(rows).reshape(-1, 3)


def _covers(box, markers: np.ndarray) -> bool:
    """Whether ``box`` overlaps one of the marker discs."""
    if not len(markers):
        return False
    dx = np.maximum(np.maximum(box.x0 - markers[:, 0], markers[:, 0] - box.x1), 0.0)
    dy = np.maximum(np.maximum(box.y0 - markers[:, 1], markers[:, 1] - box.y1), 0.0)
    return bool((np.hypot(dx, dy) < markers[:, 2] - 0.5).any())


def layout_problems(fig) -> list[str]:
    """What reads badly in ``fig``: text outside the figure, two labels (or a label and a legend)
    overlapping, a point label over a marker, an axis label without a unit."""
    fig.canvas.draw()
    problems = []
    page = fig.bbox
    texts = _texts(fig)
    for what, box, _ in texts:
        if box.x0 < page.x0 - 1 or box.y0 < page.y0 - 1 or box.x1 > page.x1 + 1 or box.y1 > page.y1 + 1:
            problems.append(f"{what} runs off the figure")
    for (wa, a, _), (wb, b, _) in itertools.combinations(texts, 2):
        if _overlap(a, b):
            problems.append(f"{wa} overlaps {wb}")
    for what, box, artist in texts:
        if isinstance(artist, Annotation) and artist.axes is not None and _covers(box, _markers(artist.axes)):
            problems.append(f"{what} covers a marker")
    for ax in fig.axes:
        if not ax.get_visible() or not ax.axison:
            continue
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            if label.strip() and not UNIT.search(label):
                problems.append(f"axis label {label!r} has no unit ('quantity, unit'; '-' if dimensionless)")
    return problems


#: where a point label may go, in points from its point: right, above, left, below, the diagonals
_OFFSETS = [(6, 2), (6, -8), (-6, 2), (-6, -8), (0, 7), (0, -11), (9, 8), (-9, 8), (9, -14), (-9, -14),
            (14, -3), (-14, -3), (0, 14), (0, -18)]


def place_labels(ax, xs, ys, labels, color, fontsize: float = 6, drawn: bool = False) -> int:
    """Label points with short texts, each at the first of a few spots around its point where it
    lies inside the axes clear of every marker and of the labels already placed; a label with
    no free spot is left out. Call once the axes' scales, limits and layout are final (titles,
    legends); returns how many were left out. ``drawn``: the figure was drawn since its layout
    became final (the labels take no part in the layout, so several calls on one figure need
    one draw, each a second or more on a busy figure)."""
    fig = ax.figure
    if not drawn:
        fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    markers = _markers(ax)
    placed = [a.get_window_extent(renderer) for a in ax.texts if isinstance(a, Annotation)]
    left_out = 0
    for x, y, label in zip(xs, ys, labels):
        for dx, dy in _OFFSETS:
            ha = "left" if dx > 0 else "right" if dx < 0 else "center"
            a = ax.annotate(label, (x, y), textcoords="offset points", xytext=(dx, dy), fontsize=fontsize,
                            color=color, ha=ha, va="bottom", in_layout=False)  # the layout is final
            box = a.get_window_extent(renderer)
            if (ax.bbox.x0 <= box.x0 and box.x1 <= ax.bbox.x1 and ax.bbox.y0 <= box.y0 and box.y1 <= ax.bbox.y1
                    and not _covers(box, markers) and not any(_overlap(box, p, 0.0) for p in placed)):
                placed.append(box)
                break
            a.remove()
        else:
            left_out += 1
    return left_out


def plane_labels(case) -> tuple[str, str]:
    """The axes of the plane a case's plastic zones are drawn in, with the length unit."""
    unit = case.unit_of("u")
    if case.body == "ring":
        return (f"r, {unit}", f"z, {unit}") if case.axisymmetric else (f"x, {unit}", f"y, {unit}")
    return f"x3 (along the prism), {unit}", f"height, {unit}"


def plastic_zones(rows: dict[str, list], path: Path, title: str, case) -> Path:
    """One row of panels per solver (label -> snapshots of :mod:`smfem.runs.zones`), one panel per
    time: cells whose mean equivalent plastic strain reaches 0.1 % coloured by it on one scale
    for all rows, each panel titled with the zone's area and the largest point value (what the
    ``peps_max`` probe gives: it passes 0.1 % before a cell's mean does, so both are named);
    cut-out cells (a snapshot's ``solid`` = 0) filled in every row, so the reference's holes
    are drawn as well. Axes and areas in ``case``'s length unit."""
    axes_labels, length_unit = plane_labels(case), case.unit_of("u")
    rows = {label: snaps for label, snaps in rows.items() if snaps}
    vmax = max([100 * s.peps.max() for snaps in rows.values() for s in snaps] + [0.2])
    ncol = max(len(snaps) for snaps in rows.values())
    cutouts = next((s.poly[~s.solid_cells] for snaps in rows.values() for s in snaps
                    if not s.solid_cells.all()), np.empty((0, 4, 2)))
    fig, axes = subplots(len(rows), ncol, figsize=(4.4 * ncol + 0.9, 4.8 * len(rows) + 0.5), squeeze=False,
                             layout="compressed")  # the layout for equal-aspect panels
    cells = None
    for axrow, (label, snaps) in zip(axes, rows.items()):
        for ax in axrow[len(snaps):]:
            ax.axis("off")
        for ax, snap in zip(axrow, snaps):
            poly, value, solid = snap.poly, snap.peps, snap.solid_cells
            ax.add_collection(PolyCollection(poly[solid], facecolors="none", edgecolors="0.85", linewidths=0.1))
            if len(cutouts):  # filled, not hatched: thousands of hatched cells took seconds per panel
                ax.add_collection(PolyCollection(cutouts, facecolors=CUTOUT, edgecolors="none"))
            hot = solid & (value >= THRESHOLD)
            cells = PolyCollection(poly[hot], array=100 * value[hot], cmap="inferno_r", clim=(0.1, vmax),
                                   edgecolors="none")
            ax.add_collection(cells)
            ax.autoscale()
            ax.set_aspect("equal")
            ax.set_title(f"{label}, t = {1e3 * snap.t:.4g} ms\nplastic area {_area(plastic_area(snap))} "
                         f"{length_unit}\u00b2 (cell means >= 0.1 %)\nlargest point value {100 * snap.peak:.3g} %",
                         fontsize=8)
            ax.set_xlabel(axes_labels[0], fontsize=7)
            ax.set_ylabel(axes_labels[1], fontsize=7)
            ax.tick_params(labelsize=6)
            ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(4))
    bar = fig.colorbar(cells, ax=axes.ravel().tolist(), shrink=0.8)
    bar.set_label("equivalent plastic strain (cell mean), %", fontsize=8)
    bar.ax.tick_params(labelsize=7)
    if len(cutouts):
        axes[0, 0].legend(handles=[matplotlib.patches.Patch(facecolor=CUTOUT, label="cut-out")], fontsize=7,
                          loc="lower left")
    fig.suptitle(title, fontsize=10)
    return save(fig, path, dpi=130)


def _area(a: float) -> str:
    return "0" if a == 0 else f"{a:.3g}" if 1e-3 <= abs(a) < 1e4 else f"{a:.2e}"
