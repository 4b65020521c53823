"""Per case: the total error of every run against the truth, the work-precision front and the
cost to reach each target; beside it the same-dt (spatial) comparison with the finest
reference run, as the paper made it, and the published extrema.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd

from cases import get_case

from smfem.runs.registry import SMFEM, headline_name, lookup

from smfem.studies import effectivity, metrics
from smfem.studies.jobs import NOT_AVAILABLE, NOT_INSTALLED, OK
from smfem.studies.plan import series_solvers
from .references import best_history, published_points
from smfem.studies.study import CaseRuns

#: probes whose errors make the headline measure: displacements and velocities. Stresses
#: (wave fronts, the rod's impact) and plastic strains (a local threshold quantity, zero until a
#: point yields) have their own measures and targets (:data:`FAMILIES`)
HEADLINE_FIELDS = metrics.HEADLINE_FIELDS
HEADLINE_MEASURE = "max over displacement and velocity probes of the relative max-norm error"
TOTAL, SPATIAL, PUBLISHED = "total", "spatial", "published"
#: the probe families other than the headline's: name -> (probe fields, error targets)
FAMILIES = {"stress": (("sigma",), (0.05, 0.10)), "plastic strain": (("peps",), (0.05, 0.10))}


def family_of(probe) -> str:
    """``'headline'``, ``'stress'`` or ``'plastic strain'``: the measure a probe counts in."""
    if probe.field in HEADLINE_FIELDS:
        return "headline"
    return next(name for name, (fields, _) in FAMILIES.items() if probe.field in fields)


@dataclass
class SolverSummary:
    """One solver on one case.

    ``points``: per run, ``label``, ``cpu``, ``dt``, ``total`` (headline measure against the
    truth), ``spatial`` (against the same-dt reference, runs at the case's dt only) and, per
    other family (:data:`FAMILIES`), its measure against the truth; ``front``: labels on the
    total-error work-precision front, cheapest first; ``costs``: target ->
    :class:`smfem.studies.metrics.Cost`; ``family_costs``: family -> target -> Cost.
    """

    solver: str
    status: str
    message: str
    points: pd.DataFrame
    front: list
    costs: dict
    family_costs: dict = field(default_factory=dict)


@dataclass
class CaseAnalysis:
    runs: CaseRuns
    case: object
    truth: object
    reference: object
    errors: pd.DataFrame
    solvers: dict
    orders: pd.DataFrame
    published: pd.DataFrame
    #: the error estimates against the truth (:mod:`smfem.studies.effectivity`)
    effectivity: pd.DataFrame = field(default_factory=pd.DataFrame)
    #: (solver, target) -> the timing pass's repeats of its decisive run (:mod:`reports.timing`)
    timings: dict = field(default_factory=dict)

    @property
    def available(self) -> bool:
        return any(s.status == OK for s in self.solvers.values())

    @property
    def headline_probes(self) -> list[str]:
        return [p.name for p in self.case.probes if p.field in HEADLINE_FIELDS]

    @property
    def truth_uncertainty(self) -> float:
        """The truth's uncertainty in the headline measure (NaN without a truth)."""
        return self.uncertainty_of("headline")

    def smfem_costs(self, family: str = "headline") -> dict | None:
        """Per target, SMFEM's cost with its best element there (the cheapest of the SMFEM
        family's series, :func:`smfem.studies.metrics.cheapest`): what the other solvers' speed-ups
        are measured against; None where no SMFEM series ran."""
        mine = [s for name, s in self.solvers.items() if lookup(name).family == SMFEM and s.status == OK]
        if not mine:
            return None
        costs = [s.costs if family == "headline" else s.family_costs[family] for s in mine]
        return {t: metrics.cheapest(c[t] for c in costs) for t in costs[0]}

    def competitors(self) -> dict[str, SolverSummary]:
        """The headline's rows: a solver's series each, but one row for the series that share one
        (:func:`smfem.runs.registry.headline_name`: CalculiX's procedures, the 3D reference's two
        engines), at each target the cheapest of them (:func:`merged`); a solver not installed
        here is no row."""
        groups: dict[str, dict] = {}
        for solver, s in self.solvers.items():
            if s.status != NOT_INSTALLED:
                groups.setdefault(headline_name(solver), {})[solver] = s
        return {name: merged(name, group) for name, group in groups.items()}

    def left_out(self) -> list[str]:
        """Why a series sharing a headline row with others has no runs (its solver's one line:
        a procedure that cannot take the scene), where the row's cell does not say it already."""
        rows = self.competitors()
        shared = Counter(headline_name(solver) for solver, s in self.solvers.items() if s.status != NOT_INSTALLED)
        return [f"{lookup(solver).label}: {s.message}" for solver, s in self.solvers.items()
                if s.status not in (OK, NOT_INSTALLED) and shared[headline_name(solver)] > 1
                and s.message != rows[headline_name(solver)].message]

    def probes_of(self, family: str) -> list[str]:
        return [p.name for p in self.case.probes if family_of(p) == family]

    def uncertainty_of(self, family: str) -> float:
        """The truth's uncertainty over a family's probes (NaN without a truth or a converged one)."""
        return self.truth.uncertainty_of(self.probes_of(family)) if self.truth is not None else math.nan


def merged(name: str, series: dict[str, SolverSummary]) -> SolverSummary:
    """One headline row ``name`` of ``series`` (solver -> summary; one solver's procedures or engines): at
    each target the cheapest that reaches it, else the one that came closest
    (:func:`smfem.studies.metrics.cheapest`), its cell naming the series' :attr:`variant
    <smfem.runs.registry.Solver.variant>` (``modal r2 modes 50``); every run's point; where
    none ran, the first's status and reason."""
    ran = {solver: s for solver, s in series.items() if s.status == OK}
    if not ran:
        return replace(next(iter(series.values())), solver=name)
    named = [{t: _named(c, lookup(solver).variant) for t, c in s.costs.items()} for solver, s in ran.items()]
    costs = {t: metrics.cheapest(c[t] for c in named) for t in named[0]}
    points = pd.concat([s.points for s in ran.values()], ignore_index=True)
    return SolverSummary(name, OK, "", points, [], costs)


def _named(cost: metrics.Cost, variant: str) -> metrics.Cost:
    """``cost`` with its settings led by ``variant`` (reached: ``modal r2``; missed: ``modal``)."""
    if not variant or cost.how not in (metrics.REACHED, metrics.NOT_REACHED):
        return cost
    return replace(cost, label=f"{variant} {cost.label}".strip())


def _dt(run) -> float:
    return run.summary["params"]["dt"]


def _run_rows(cr: CaseRuns, case, truth, reference, points) -> list[dict]:
    rows = []
    families = {p.name: family_of(p) for p in case.probes}
    window = case.references.get("comparison_window_s", 0.0)
    same_dt = _dt(cr.reference) if cr.reference is not None and cr.reference.summary else case.dt
    for solver, runs in cr.series.items():
        for run in runs:
            if not run.usable:
                continue
            base = {"case": case.name, "solver": solver, "level": run.label, "status": run.status,
                    "n_dof": run.summary["n_dof"], "cpu_time_s": run.summary["cpu_time_s"], "dt": _dt(run)}
            t = run.history["t"].to_numpy()
            for probe in case.probe_names:
                a = run.history[probe].to_numpy()
                if truth is not None and probe in truth.values:
                    e_max, e_l2 = (metrics.history_errors(t, a, truth.t, truth.values[probe], window)
                                   if truth.converged(probe) else (math.nan, math.nan))
                    rows.append({**base, "probe": probe, "kind": TOTAL, "against": "truth", "err_max": e_max,
                                 "err_l2": e_l2, "truth_uncertainty": truth.uncertainty[probe],
                                 "headline": families[probe] == "headline", "family": families[probe]})
                if (reference is not None and probe in reference.values and run.path != cr.reference.path
                        and math.isclose(_dt(run), same_dt, rel_tol=1e-9)):
                    e_max, e_l2 = metrics.history_errors(t, a, reference.t, reference.values[probe], window)
                    rows.append({**base, "probe": probe, "kind": SPATIAL, "against": reference.name,
                                 "err_max": e_max, "err_l2": e_l2, "headline": families[probe] == "headline",
                                 "family": families[probe]})
                for pp in (p for p in points if p.probe == probe):
                    found = metrics.extrema_near(t, a, pp.points, pp.kinds)
                    e_max, e_l2 = metrics.point_errors([v for _, v in found], [v for _, v in pp.points])
                    rows.append({**base, "probe": probe, "kind": PUBLISHED, "against": f"published: {pp.source}",
                                 "err_max": e_max, "err_l2": e_l2, "headline": False, "family": families[probe]})
    return rows


def _measure(errors: pd.DataFrame, solver: str, kind: str, family: str = "headline") -> pd.Series:
    """A family's measure per run label (max over its probes; NaN-only gives NaN)."""
    if not len(errors):
        return pd.Series(dtype=float)
    e = errors[(errors.solver == solver) & (errors.kind == kind) & (errors.family == family)]
    return e.groupby("level", sort=False)["err_max"].max()


def _solver_summary(solver, runs, errors: pd.DataFrame, uncertainty: float, family_uncertainty: dict) -> SolverSummary:
    done = [r for r in runs if r.status == OK]
    if not done:
        refused = next((r for r in runs if r.status != OK), None)
        status = refused.status if refused else NOT_AVAILABLE
        costs = {t: metrics.cost_to(t, [], [], []) for t in metrics.TARGETS}
        family_costs = {f: {t: metrics.cost_to(t, [], [], []) for t in targets} for f, (_, targets) in FAMILIES.items()}
        return SolverSummary(solver, status, refused.message if refused else "no runs planned",
                             pd.DataFrame(), [], costs, family_costs)
    labels = [r.label for r in done]
    if len(set(labels)) < len(labels):  # errors are keyed by label: two runs would share one's error
        twice = next(lab for lab in labels if labels.count(lab) > 1)
        raise ValueError(f"{solver}: two runs are labelled {twice!r}: smfem.studies.cache.Run.label must tell them apart")
    total, spatial = _measure(errors, solver, TOTAL), _measure(errors, solver, SPATIAL)
    others = {f: _measure(errors, solver, TOTAL, f) for f in FAMILIES}
    points = pd.DataFrame([{"label": r.label, "cpu": r.summary["cpu_time_s"], "dt": _dt(r),
                            "n_dof": r.summary["n_dof"], "total": total.get(r.label, math.nan),
                            "spatial": spatial.get(r.label, math.nan),
                            **{f: m.get(r.label, math.nan) for f, m in others.items()}} for r in done]).sort_values("cpu")
    front = [points.label.iloc[i] for i in metrics.pareto_front(points.cpu.tolist(), points.total.tolist())]
    costs = {t: metrics.cost_to(t, points.cpu, points.total, points.label, uncertainty) for t in metrics.TARGETS}
    family_costs = {f: {t: metrics.cost_to(t, points.cpu, points[f], points.label, family_uncertainty[f])
                        for t in targets} for f, (_, targets) in FAMILIES.items()}
    return SolverSummary(solver, OK, "", points, front, costs, family_costs)


def _orders(case, solver: str, s: SolverSummary) -> list[dict]:
    """Observed orders of the headline measure: total error against dt at each fixed mesh,
    spatial error against the mesh at the case's dt."""
    if s.status != OK or not len(s.points):
        return []
    rows = []
    pts = s.points.assign(space=s.points.label.str.replace(r" dt\S+", "", regex=True))
    for space, group in pts.groupby("space", sort=False):
        group = group[np.isfinite(group.total)]
        if group.dt.nunique() >= 2:
            order = metrics.observed_order(group.dt, group.total)
            rows.append({"case": case.name, "solver": solver, "error": TOTAL, "h": "dt", "fixed": space,
                         "levels": len(group), "order": order, "reading": _reading(order)})
    same = pts[np.isfinite(pts.spatial)]
    if len(same) >= 2:
        order = metrics.observed_order(same.n_dof ** -0.5, same.spatial)
        rows.append({"case": case.name, "solver": solver, "error": SPATIAL, "h": "dof^(-1/2)", "fixed": "case dt",
                     "levels": len(same), "order": order, "reading": _reading(order, "the mesh")})
    return rows


#: below this observed order a ladder's error hardly falls: another error dominates it
FLAT_ORDER = 0.5


def _reading(order: float, ladder: str = "the step") -> str:
    """What an observed order says, for a reader who meets a negative one."""
    if not np.isfinite(order):
        return ""
    if order < 0:
        return (f"the error grows slightly as {ladder} is refined: another error dominates (at a fixed mesh, "
                "the space error) and the refined part no longer offsets it")
    if order < FLAT_ORDER:
        return f"flat: the error is not limited by {ladder} here, another error dominates"
    return ""


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
    reference = best_history(case, cr.reference) if cr.reference is not None else None
    points = published_points(case)
    errors = pd.DataFrame(_run_rows(cr, case, cr.truth, reference, points))
    an = CaseAnalysis(cr, case, cr.truth, reference, errors, {}, pd.DataFrame(), pd.DataFrame())
    family_uncertainty = {f: an.uncertainty_of(f) for f in FAMILIES}
    an.solvers = {s: _solver_summary(s, cr.series.get(s, []), errors, an.truth_uncertainty, family_uncertainty)
                  for s in series_solvers() if s in cr.series}
    an.orders = pd.DataFrame([row for solver, s in an.solvers.items() for row in _orders(case, solver, s)])
    an.published = pd.DataFrame(_published_rows(case, cr, points))
    an.effectivity = pd.DataFrame(effectivity.rows(case, cr.truth, cr.estimates))
    return an
