"""Error measures, observed orders, Richardson extrapolation, work-precision fronts, cost to a target."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from smfem.runs.errors import common_grid, history_errors, inside_window, moving_average, smoothed  # noqa: F401 - used here and re-exported


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


#: the probes of the headline measure: displacements and velocities (stresses and plastic
#: strains have their own families, singular ones among them)
HEADLINE_FIELDS = ("u", "v")


def headline_errors(case, truth, t, history) -> dict[str, float]:
    """The relative max-norm error of one run (``t``, ``history[probe]``) against ``truth`` on
    each of the case's displacement and velocity probes that the truth has converged, through
    the case's comparison window."""
    window = case.references.get("comparison_window_s", 0.0)
    return {p.name: history_errors(t, np.asarray(history[p.name]), truth.t, truth.values[p.name], window)[0]
            for p in case.probes if p.field in HEADLINE_FIELDS and p.name in truth.values and truth.converged(p.name)}


def headline_error(case, truth, t, history) -> float:
    """The headline measure of one run against ``truth``: the largest of :func:`headline_errors`;
    NaN where the truth has converged none."""
    errors = headline_errors(case, truth, t, history)
    return max(errors.values()) if errors else math.nan


#: error levels of the headline: CPU time to reach each
TARGETS = (0.01, 0.05)
#: a target is checked only if it is at least this many times the truth's uncertainty
TRUTH_MARGIN = 3.0
REACHED, NOT_REACHED, TRUTH_TOO_COARSE, NO_RUN = "reached", "not reached", "truth not fine enough", "no run"


def pareto_front(cpu, err) -> list[int]:
    """Indices of the runs on the work-precision front: sorted by CPU time, each with a smaller
    error than every cheaper run (non-finite errors left out)."""
    order = sorted((c, e, i) for i, (c, e) in enumerate(zip(cpu, err)) if math.isfinite(e) and c > 0)
    front, best = [], math.inf
    for c, e, i in order:
        if e < best:
            front.append(i)
            best = e
    return front


@dataclass(frozen=True)
class Cost:
    """What it costs one solver to reach an error ``target``.

    ``how``: ``'reached'`` (``cpu`` s, the CPU time of the cheapest run below the target, and
    ``label``, its settings), ``'not reached'`` (``cpu`` = the dearest run's time, ``best`` =
    the smallest error, ``label`` empty or the series a shared cell names),
    ``'truth not fine enough'`` (the target is below :data:`TRUTH_MARGIN`
    times the truth's uncertainty: no run can be said to reach it) or ``'no run'``.
    """

    target: float
    how: str
    cpu: float
    label: str
    best: float

    def text(self) -> str:
        if self.how == REACHED:
            return f"{self.cpu:.3g} ({self.label})"
        if self.how == NOT_REACHED:
            return f"not reached (best {100 * self.best:.2g} %{', ' + self.label if self.label else ''})"
        return self.how


def cost_to(target: float, cpu, err, labels, truth_uncertainty: float = 0.0) -> Cost:
    """The cheapest run of a series whose error is at most ``target``."""
    runs = [(c, e, lab) for c, e, lab in zip(cpu, err, labels) if math.isfinite(e) and c > 0]
    if not runs:
        return Cost(target, NO_RUN, math.nan, "", math.nan)
    best = min(e for _, e, _ in runs)
    if not (target >= TRUTH_MARGIN * truth_uncertainty):  # NaN uncertainty: no truth to check against
        return Cost(target, TRUTH_TOO_COARSE, math.nan, "", best)
    below = sorted((c, lab) for c, e, lab in runs if e <= target)
    if below:
        return Cost(target, REACHED, below[0][0], below[0][1], best)
    return Cost(target, NOT_REACHED, max(c for c, _, _ in runs), "", best)


def cheapest(costs) -> Cost:
    """The best of several series' costs to one target (SMFEM's elements): the cheapest that
    reaches it, else the one that came closest, else the first."""
    costs = list(costs)
    reached = [c for c in costs if c.how == REACHED]
    if reached:
        return min(reached, key=lambda c: c.cpu)
    missed = [c for c in costs if c.how == NOT_REACHED]
    return min(missed, key=lambda c: c.best) if missed else costs[0]


def speedup(reference: Cost, smfem: Cost) -> str:
    """``reference / smfem`` CPU time to the same target, as a value or a bound (``> x``: the
    reference does not reach it even at its dearest run; ``< x``: SMFEM does not)."""
    if TRUTH_TOO_COARSE in (reference.how, smfem.how) or NO_RUN in (reference.how, smfem.how):
        return ""
    if reference.how == REACHED and smfem.how == REACHED:
        return f"{reference.cpu / smfem.cpu:.3g}x"
    if smfem.how == REACHED:
        return f"> {reference.cpu / smfem.cpu:.3g}x"
    if reference.how == REACHED:
        return f"< {reference.cpu / smfem.cpu:.3g}x"
    return "neither reaches it"
