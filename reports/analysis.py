"""Per case: errors of every run against the case's reference, orders, Richardson, cost to 1 %."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from cases import get_case

from . import metrics
from .jobs import NOT_AVAILABLE, OK
from .plan import RESOLUTION_KEYS, SMFEM, SOLVERS
from .references import best_history, published_points
from .study import CaseRuns

#: probes whose errors make the headline measure: the equivalent plastic strain at a point is
#: a local threshold quantity (zero until the point yields), reported per probe only
HEADLINE_FIELDS = ("u", "v", "sigma")
HEADLINE_MEASURE = "max over displacement, velocity and stress probes of the relative max-norm error"


def _h(runs) -> tuple[str, list[float]]:
    """The resolution parameter of a series and its mesh-size-like value per run (1/refine,
    1/harmonics or dt): the key with the most distinct values along the series (the first of
    refine, harmonics, dt on a tie); ``''`` when none varies."""
    params = [r.summary["params"] for r in runs]
    distinct = {key: len({p[key] for p in params}) for key in RESOLUTION_KEYS}
    key = max(RESOLUTION_KEYS, key=lambda k: distinct[k])  # max keeps the first of equals
    if distinct[key] < 2:
        return "", [math.nan] * len(runs)
    return ("dt", [p["dt"] for p in params]) if key == "dt" else (f"1/{key}", [1.0 / p[key] for p in params])


def _peak(x: np.ndarray) -> float:
    """The signed value of largest magnitude."""
    return float(x[np.argmax(np.abs(x))])


@dataclass
class SolverSummary:
    """One solver on one case: work-precision points and the cost to reach the tolerance."""

    solver: str
    cpu: list
    error: list
    labels: list
    cost: metrics.Cost
    status: str
    message: str = ""


@dataclass
class CaseAnalysis:
    runs: CaseRuns
    case: object
    reference: object
    errors: pd.DataFrame
    solvers: dict
    orders: pd.DataFrame
    richardson: pd.DataFrame
    published: pd.DataFrame

    @property
    def available(self) -> bool:
        return any(s.status == OK for s in self.solvers.values())


def _run_rows(cr: CaseRuns, case, reference, points) -> list[dict]:
    rows = []
    headline = {p.name for p in case.probes if p.field in HEADLINE_FIELDS}
    for solver, runs in cr.series.items():
        for run in runs:
            if not run.usable or run.path == cr.reference.path:  # the reference has no error
                continue
            base = {"case": case.name, "solver": solver, "level": run.label, "status": run.status,
                    "n_dof": run.summary["n_dof"], "cpu_time_s": run.summary["cpu_time_s"]}
            t = run.history["t"].to_numpy()
            for probe in case.probe_names:
                a = run.history[probe].to_numpy()
                if reference is not None and probe in reference.values:
                    e_max, e_l2 = metrics.history_errors(t, a, reference.t, reference.values[probe],
                                                         case.references.get("comparison_window_s", 0.0))
                    rows.append({**base, "probe": probe, "reference": reference.name, "err_max": e_max,
                                 "err_l2": e_l2, "headline": probe in headline})
                for pp in (p for p in points if p.probe == probe):
                    found = metrics.extrema_near(t, a, pp.points, pp.kinds)
                    e_max, e_l2 = metrics.point_errors([v for _, v in found], [v for _, v in pp.points])
                    rows.append({**base, "probe": probe, "reference": f"published: {pp.source}",
                                 "err_max": e_max, "err_l2": e_l2, "headline": False})
    return rows


def _solver_summary(solver, runs, errors: pd.DataFrame) -> SolverSummary:
    done = [r for r in runs if r.status == OK]
    if not done:
        refused = next((r for r in runs if r.status != OK), None)
        status = refused.status if refused else NOT_AVAILABLE
        return SolverSummary(solver, [], [], [], metrics.time_to_tolerance([], []), status,
                             refused.message if refused else "no runs planned")
    mine = errors[(errors.solver == solver) & errors.headline & (errors.status == OK)] if len(errors) else errors
    worst = mine.groupby("level", sort=False).agg(cpu=("cpu_time_s", "first"), err=("err_max", "max")) \
        if len(mine) else pd.DataFrame(columns=["cpu", "err"])
    worst = worst.sort_values("cpu")
    return SolverSummary(solver, worst.cpu.tolist(), worst.err.tolist(), worst.index.tolist(),
                         metrics.time_to_tolerance(worst.cpu, worst.err), OK)


def _orders(case, solver, runs, errors) -> list[dict]:
    runs = [r for r in runs if r.status == OK]
    if len(runs) < 2:
        return []
    name, h = _h(runs)
    by_level = {r.label: hv for r, hv in zip(runs, h)}
    rows = []
    for probe, group in errors[(errors.solver == solver) & ~errors.reference.str.startswith("published")].groupby("probe"):
        hv = [by_level.get(level, math.nan) for level in group.level]
        rows.append({"case": case.name, "solver": solver, "probe": probe, "h": name, "levels": len(group),
                     "reference": group.reference.iloc[0],
                     "order_max": metrics.observed_order(hv, group.err_max),
                     "order_l2": metrics.observed_order(hv, group.err_l2)})
    return rows


def _richardson(case, solver, runs, reference) -> list[dict]:
    runs = [r for r in runs if r.status == OK]
    name, h = _h(runs)
    if len(set(h)) < 3 or not name:
        return []
    # peaks over the window every run and the reference cover (a run may stop early)
    end = min([r.history["t"].iloc[-1] for r in runs] + ([reference.t[-1]] if reference is not None else []))
    rows = []
    for probe in case.probe_names:
        q = [_peak(r.history[probe].to_numpy()[r.history["t"].to_numpy() <= end]) for r in runs]
        fit = metrics.richardson(h, q)
        finest = q[int(np.argmin(h))]
        ref_peak = (_peak(reference.values[probe][reference.t <= end])
                    if reference is not None and probe in reference.values else math.nan)
        rows.append({"case": case.name, "solver": solver, "probe": probe, "quantity": "peak value", "h": name,
                     "finest": finest, "order": fit.order if fit else math.nan,
                     "extrapolated": fit.q_star if fit else math.nan,
                     "finest_vs_extrapolated": fit.error_of(finest) if fit else math.nan,
                     "reference_peak": ref_peak,
                     "extrapolated_vs_reference": abs(fit.q_star - ref_peak) / abs(ref_peak)
                     if fit and ref_peak else math.nan,
                     "note": "" if fit else "not in the asymptotic range (differences change sign)"})
    return rows


def _published_rows(case, cr: CaseRuns, points) -> list[dict]:
    rows = []
    for pp in points:
        for solver, runs in cr.series.items():
            for run in (r for r in runs if r.usable):
                t, a = run.history["t"].to_numpy(), run.history[pp.probe].to_numpy()
                for (tp, vp), kind, (tf, vf) in zip(pp.points, pp.kinds, metrics.extrema_near(t, a, pp.points, pp.kinds)):
                    rows.append({"case": case.name, "solver": solver, "level": run.label, "probe": pp.probe,
                                 "kind": kind, "t_published": tp, "published": vp, "t_found": tf, "found": vf,
                                 "difference": vf - vp, "source": pp.source})
    return rows


def analyse(cr: CaseRuns) -> CaseAnalysis:
    """Every measure the report shows for one case."""
    case = get_case(cr.study.case, cr.study.base)
    reference = best_history(case, cr.reference)
    points = published_points(case)
    errors = pd.DataFrame(_run_rows(cr, case, reference, points))
    solvers = {s: _solver_summary(s, cr.series.get(s, []), errors) for s in SOLVERS if s in cr.series}
    orders, rich = [], []
    for solver, runs in cr.series.items():
        if len(errors):
            orders += _orders(case, solver, runs, errors)
        rich += _richardson(case, solver, runs, reference)
    return CaseAnalysis(cr, case, reference, errors, solvers, pd.DataFrame(orders), pd.DataFrame(rich),
                        pd.DataFrame(_published_rows(case, cr, points)))
