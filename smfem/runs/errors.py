"""How far one history is from another: the one definition every comparison uses.

Relative max-norm ``max|a - b| / max|b|`` (and L2) over the common window, on the coarser of
the two time grids; for plastic-strain probes the relative difference of the peaks.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import trapezoid


def moving_average(x: np.ndarray, width: int) -> np.ndarray:
    """Centred moving average over ``width`` samples (an odd count: ``width // 2`` each side);
    near the ends over the samples there are, so an end sample is not held over a window."""
    x = np.asarray(x, float)
    half = width // 2
    if half < 1:
        return x
    total = np.concatenate([[0.0], np.cumsum(x)])
    i = np.arange(x.size)
    lo, hi = np.maximum(i - half, 0), np.minimum(i + half + 1, x.size)
    return (total[hi] - total[lo]) / (hi - lo)


def common_grid(t: np.ndarray, a: np.ndarray, t_ref: np.ndarray, b: np.ndarray):
    """Both histories on the coarser of the two time grids, over their common window.

    A time-stepping run is known at its own steps only: on nested grids (dt halvings) this
    compares at the coarser run's steps exactly, without interpolating between them.
    Returns ``(times, a, b)``.
    """
    end = min(t[-1], t_ref[-1]) * (1 + 1e-12)
    coarse_is_run = len(t) > 1 and len(t_ref) > 1 and np.median(np.diff(t)) > np.median(np.diff(t_ref)) * (1 + 1e-9)
    grid = t if coarse_is_run else t_ref
    grid = grid[grid <= end]
    return grid, np.interp(grid, t, a), np.interp(grid, t_ref, b)


def smoothed(x: np.ndarray, grid: np.ndarray, window: float) -> np.ndarray:
    """``x`` (sampled on ``grid``) seen through a triangular window ``window`` s wide: two
    moving averages half that long. Its side lobes fall as the square of the frequency (one
    moving average's only as the frequency), so ringing shorter than the window, which no
    mesh resolves alike, is left out, and what is longer is kept. Unchanged when ``window``
    is 0."""
    if window <= 0 or len(grid) < 2:
        return x
    width = int(round(0.5 * window / np.median(np.diff(grid))))
    return moving_average(moving_average(x, width), width)


def inside_window(grid: np.ndarray, window: float) -> np.ndarray:
    """Mask of the samples of ``grid`` at least half a ``window`` from both of its ends: where
    the window fits whole. Near an end :func:`smoothed` averages over the samples there are, a
    one-sided window with a hard edge that lets ringing through (falling as the frequency, not
    its square: measured on rod_collision, the mesh-scale ringing of a record's last sample is
    what made its mid-target stress look divergent over the explicit ladder). All of it when
    ``window`` is 0."""
    grid = np.asarray(grid, float)
    if window <= 0 or len(grid) < 2:
        return np.ones(grid.shape, bool)
    tol = 1e-9 * window
    return (grid >= grid[0] + 0.5 * window - tol) & (grid <= grid[-1] - 0.5 * window + tol)


def history_errors(t: np.ndarray, a: np.ndarray, t_ref: np.ndarray, b: np.ndarray,
                   window: float = 0.0) -> tuple[float, float]:
    """Relative max-norm and L2 errors of history ``a`` against ``b`` over their common window.

    ``max|a - b| / max|b|`` and ``sqrt(int (a - b)^2 dt / int b^2 dt)``, on the coarser of
    the two time grids (:func:`common_grid`), so runs with another ``dt`` compare too.
    ``window`` (s): each history is first seen through a window that wide (:func:`smoothed`,
    on its own time grid, so a finely sampled history is averaged, not sampled), for scenes
    whose shorter features no model converges on (the case's
    ``references['comparison_window_s']``, e.g. the rod's 2R/c), and compared where the
    window fits whole (:func:`inside_window`). NaN when the reference is identically zero or
    the windows do not overlap.
    """
    a, b = smoothed(a, t, window), smoothed(b, t_ref, window)
    grid, a, b = common_grid(t, a, t_ref, b)
    keep = inside_window(grid, window)
    grid, a, b = grid[keep], a[keep], b[keep]
    if len(grid) < 2 or not np.any(b):
        return math.nan, math.nan
    d = a - b
    norm = trapezoid(b * b, grid)  # 0 where b is non-zero at a single end sample only
    l2 = math.sqrt(trapezoid(d * d, grid) / norm) if norm > 0 else math.nan
    return float(np.abs(d).max() / np.abs(b).max()), l2


def probe_error(name: str, t: np.ndarray, a: np.ndarray, t_ref: np.ndarray, b: np.ndarray,
                window: float = 0.0) -> tuple[str, float]:
    """Which measure applies to probe ``name`` and its value, for ``a`` against ``b``: the
    relative difference of the peaks for plastic strains (``peps*``), which sit on a point
    whose history is a ramp; else the relative max-norm of :func:`history_errors` (through
    ``window``)."""
    if name.startswith("peps"):
        end = min(t[-1], t_ref[-1]) * (1 + 1e-12)
        pa, pb = np.max(a[t <= end]), np.max(b[t_ref <= end])
        return "peak difference", float((pa - pb) / pb) if pb > 0 else math.nan
    return "max-norm", history_errors(t, a, t_ref, b, window)[0]
