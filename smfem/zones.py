"""Plastic-zone snapshots of an SMFEM run (:class:`cases.result.ZoneSnapshot`): cells in the
plotting plane and their equivalent plastic strain."""

from __future__ import annotations

import math

import numpy as np

from cases.result import ZONE_THRESHOLD, ZoneSnapshot

from .inhomogeneity import cut_edges, element_factor


def smfem_snapshot(t: float, model, case, peps: np.ndarray, x3: np.ndarray) -> ZoneSnapshot:
    """Snapshot of SMFEM's ``peps`` (elements, section points, the x3 points ``x3``): per cell
    the element mean (a zone area that converges with the mesh), and ``peak``, the largest
    point value (the quantity of the ``peps_max`` probe, past 0.1 % before any mean is).

    Along x3 the element means are drawn as the line through the points (:func:`along_x3`):
    cells run from point to point, split where the line crosses the zone threshold, so the
    zone's area is that of the interpolated field and converges as the points' spacing
    squared, not as one slice around each point (which moved the thick cylinder's area by
    5.6 % from 32 to 64 points while its probes moved by 1e-3). An axisymmetric section shows
    the largest value along x3 (they are all equal).
    """
    X, value, peak = model.mesh.element_x(), peps.mean(axis=1), float(peps.max())  # (ne, nodes, 2), (ne, nq)
    if case.body == "ring" and case.axisymmetric:
        return ZoneSnapshot(t, X, value.max(axis=1), peak, np.ones(len(X), bool))
    element, interval, a, b, mean, mids = along_x3(value, x3, case)
    solid = element_factor(case, model.mesh, mids)[element, interval] == 1.0
    lo1, hi1 = X[:, :, 0].min(1)[element], X[:, :, 0].max(1)[element]
    lo2, hi2 = X[:, :, 1].min(1)[element], X[:, :, 1].max(1)[element]
    if case.body == "ring":  # a plane section: wedges in x-y
        ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
        poly = np.stack([np.stack([lo1 * ca, lo1 * sa], -1), np.stack([hi1 * ca, hi1 * sa], -1),
                         np.stack([hi1 * cb, hi1 * sb], -1), np.stack([lo1 * cb, lo1 * sb], -1)], axis=1)
    else:  # span x height
        poly = np.stack([np.stack([a, lo2], -1), np.stack([b, lo2], -1), np.stack([b, hi2], -1),
                         np.stack([a, hi2], -1)], axis=1)
    return ZoneSnapshot(t, poly, mean, peak, solid)


def along_x3(value: np.ndarray, x3: np.ndarray, case, threshold: float = ZONE_THRESHOLD):
    """Cells along x3 of the piecewise-linear line through ``value`` (n_elements, n) at the
    sorted points ``x3`` over the period: per cell its element, the interval between knots it
    lies in, ``a`` and ``b`` (its x3 ends) and the line's mean over it, each a flat array; and
    the intervals' midpoints, within the period.

    The line is held constant from the outermost points of a piece to its ends (a cut-out's
    edge, where the material jumps; a prism's ends), wraps around a ring, and is cut where it
    crosses ``threshold``: every cell lies wholly on one side, so the cells at or above it
    cover exactly where the line is.
    """
    period = 2 * math.pi if case.body == "ring" else case.length
    edges = cut_edges(case, 0.0, period)[1:-1]
    if case.body == "ring":  # the last interval wraps to the first point, one period on
        knots, index = np.append(x3, x3[0] + period), np.append(np.arange(len(x3)), 0)
        edges = np.where(edges < x3[0], edges + period, edges)
    else:
        knots, index = np.concatenate([[0.0], x3, [period]]), np.concatenate([[0], np.arange(len(x3)), [len(x3) - 1]])
    # a piece's edge between two points: the value of the point on each side, up to it
    gap = np.searchsorted(knots, edges)  # edge lies between knots[gap - 1] and knots[gap]
    inside = (gap > 0) & (gap < len(knots)) & ~np.isin(edges, knots)
    gap, edges = gap[inside], edges[inside]
    knots = np.insert(knots, np.repeat(gap, 2), np.repeat(edges, 2))
    index = np.insert(index, np.repeat(gap, 2), np.column_stack([index[gap - 1], index[gap]]).ravel())
    v = value[:, index]  # (ne, knots)
    p, q = v[:, :-1], v[:, 1:]
    a, b = np.broadcast_to(knots[:-1], p.shape), np.broadcast_to(knots[1:], p.shape)
    element = np.broadcast_to(np.arange(len(value))[:, None], p.shape)
    interval = np.broadcast_to(np.arange(p.shape[1]), p.shape)
    keep = b > a
    crossing = keep & ((p - threshold) * (q - threshold) < 0)
    c = a + (threshold - p) / np.where(crossing, q - p, 1.0) * (b - a)
    whole = keep & ~crossing
    cells = [(element[whole], interval[whole], a[whole], b[whole], 0.5 * (p + q)[whole]),
             (element[crossing], interval[crossing], a[crossing], c[crossing], 0.5 * (p[crossing] + threshold)),
             (element[crossing], interval[crossing], c[crossing], b[crossing], 0.5 * (threshold + q[crossing]))]
    return tuple(np.concatenate(parts) for parts in zip(*cells)) + ((0.5 * (knots[:-1] + knots[1:])) % period,)
