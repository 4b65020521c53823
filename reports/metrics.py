"""Error measures, observed orders, Richardson extrapolation, cost to reach a tolerance."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import trapezoid
from scipy.optimize import brentq

#: error level of the headline table
TOLERANCE = 0.01


def moving_average(x: np.ndarray, width: int) -> np.ndarray:
    """Centred moving average over ``width`` samples, the ends held (no shrink at the edges)."""
    if width < 2:
        return np.asarray(x, float)
    padded = np.concatenate([np.full(width, x[0]), x, np.full(width, x[-1])])
    return np.convolve(padded, np.ones(width) / width, mode="same")[width:-width]


def history_errors(t: np.ndarray, a: np.ndarray, t_ref: np.ndarray, b: np.ndarray,
                   window: float = 0.0) -> tuple[float, float]:
    """Relative max-norm and L2 errors of history ``a`` against ``b`` over their common window.

    ``max|a - b| / max|b|`` and ``sqrt(int (a - b)^2 dt / int b^2 dt)``, with ``a`` linearly
    interpolated to the reference times ``t_ref`` (runs with another ``dt`` compare too).
    ``window`` (s): both histories are first seen through a moving average that long, for
    scenes whose shorter features no model converges on (the case's
    ``references['comparison_window_s']``, e.g. the rod's 2R/c). NaN when the reference is
    identically zero or the windows do not overlap.
    """
    end = min(t[-1], t_ref[-1])
    keep = t_ref <= end * (1 + 1e-12)
    tr, b = t_ref[keep], b[keep]
    if len(tr) < 2 or not np.any(b):
        return math.nan, math.nan
    a = np.interp(tr, t, a)
    if window > 0:
        width = int(round(window / np.median(np.diff(tr))))
        a, b = moving_average(a, width), moving_average(b, width)
    d = a - b
    l2 = math.sqrt(trapezoid(d * d, tr) / trapezoid(b * b, tr))
    return float(np.abs(d).max() / np.abs(b).max()), l2


def extrema_near(t: np.ndarray, a: np.ndarray, points, kinds) -> list[tuple[float, float]]:
    """For each published extremum ``(t_i, b_i)`` of kind ``'min'``/``'max'``, the extremum of
    that kind of the history ``a`` between the midpoints to the neighbouring published times
    (a curve read off a figure fixes times only roughly); NaN where the history ends before t_i."""
    times = np.array([p[0] for p in points])
    bounds = np.concatenate([[0.0], 0.5 * (times[1:] + times[:-1]), [np.inf]])
    found = []
    for t_i, lo, hi, kind in zip(times, bounds[:-1], bounds[1:], kinds):
        inside = np.flatnonzero((t >= lo) & (t <= hi))
        if inside.size == 0 or t[-1] < t_i:
            found.append((math.nan, math.nan))
            continue
        k = inside[np.argmin(a[inside]) if kind == "min" else np.argmax(a[inside])]
        found.append((float(t[k]), float(a[k])))
    return found


def point_errors(values, published) -> tuple[float, float]:
    """Relative max-norm and L2 (root-mean-square) errors over a set of published values."""
    a, b = np.asarray(values, float), np.asarray(published, float)
    if np.isnan(a).any():
        return math.nan, math.nan
    return float(np.abs(a - b).max() / np.abs(b).max()), float(np.sqrt(((a - b) ** 2).sum() / (b * b).sum()))


def observed_order(h, err) -> float:
    """Slope of the least-squares line through ``log err`` against ``log h`` (positive and
    finite errors only); NaN with fewer than two such points."""
    h, err = np.asarray(h, float), np.asarray(err, float)
    ok = np.isfinite(err) & (err > 0) & (h > 0)
    if np.unique(h[ok]).size < 2:
        return math.nan
    return float(np.polyfit(np.log(h[ok]), np.log(err[ok]), 1)[0])


@dataclass(frozen=True)
class Richardson:
    """``q(h) = q_star + C h^p`` through three levels."""

    order: float
    q_star: float

    def error_of(self, q: float) -> float:
        """Estimated relative error of ``q`` (a level's value) against ``q_star``."""
        return abs(q - self.q_star) / abs(self.q_star) if self.q_star else math.nan


def richardson(h, q) -> Richardson | None:
    """Richardson extrapolation from the three finest levels (any ratios of ``h``).

    None when the differences change sign (not in the asymptotic range) or no order in
    (0.05, 12) fits.
    """
    order = np.argsort(h)[::-1][-3:] if len(h) >= 3 else None
    if order is None:
        return None
    (h1, h2, h3), (q1, q2, q3) = np.asarray(h, float)[order], np.asarray(q, float)[order]
    d1, d2 = q1 - q2, q2 - q3
    if not (h1 > h2 > h3 > 0) or d1 * d2 <= 0:
        return None
    f = lambda p: (h1**p - h2**p) / (h2**p - h3**p) - d1 / d2
    lo, hi = 0.05, 12.0
    if f(lo) * f(hi) > 0:
        return None
    p = brentq(f, lo, hi)
    return Richardson(p, q3 - d2 * h3**p / (h2**p - h3**p))


@dataclass(frozen=True)
class Cost:
    """CPU time to reach a tolerance, as an interval ``[lo, hi]`` in s.

    ``how``: ``'interpolated'`` (lo = hi, log-log between the levels either side),
    ``'coarsest'`` (already below at the cheapest level: lo = 0, hi its time) or
    ``'not reached'`` (lo = the dearest level's time, hi = inf; ``best`` is the smallest error).
    """

    lo: float
    hi: float
    how: str
    best: float

    def text(self) -> str:
        if self.how == "interpolated":
            return f"{self.hi:.3g}"
        if self.how == "coarsest":
            return f"<= {self.hi:.3g}"
        return f"not reached (best {100 * self.best:.2g} %)" if math.isfinite(self.best) else "no run to compare"


def time_to_tolerance(cpu, err, tol: float = TOLERANCE) -> Cost:
    """Where the work-precision curve (levels sorted by CPU time) first crosses ``tol``."""
    pts = sorted((c, e) for c, e in zip(cpu, err) if math.isfinite(e) and c > 0)
    if not pts:
        return Cost(0.0, math.inf, "not reached", math.nan)
    best = min(e for _, e in pts)
    if pts[0][1] <= tol:
        return Cost(0.0, pts[0][0], "coarsest", best)
    for (c0, e0), (c1, e1) in zip(pts, pts[1:]):
        if e1 <= tol:
            s = (math.log(tol) - math.log(e0)) / (math.log(e1) - math.log(e0)) if e1 > 0 else 1.0
            t = math.exp(math.log(c0) + s * (math.log(c1) - math.log(c0)))
            return Cost(t, t, "interpolated", best)
    return Cost(pts[-1][0], math.inf, "not reached", best)


def speedup(reference: Cost, smfem: Cost) -> str:
    """``reference / smfem`` CPU time to the tolerance, as a value or a bound (``> x``, ``< x``)."""
    if not math.isfinite(smfem.best) or not math.isfinite(reference.best):
        return "n/a"
    if reference.how == smfem.how != "interpolated":
        return "neither reaches it" if smfem.how == "not reached" else "both at the coarsest level"
    lo = reference.lo / smfem.hi if smfem.hi > 0 else math.inf
    hi = reference.hi / smfem.lo if smfem.lo > 0 else math.inf
    if lo == hi:
        return f"{lo:.3g}x"
    return f"> {lo:.3g}x" if math.isinf(hi) else f"< {hi:.3g}x"
