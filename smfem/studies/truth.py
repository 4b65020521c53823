"""The truth of a case: probe histories converged in space, harmonics and time, each with an
uncertainty, so that a run's *total* error can be measured (not only its difference from
another solver at the same time step).

Three ways to make one (:class:`smfem.studies.plan.TruthPlan`):

``modal`` (linear, homogeneous along x3)
    The reference's harmonic model integrated exactly in time (:mod:`reference_fem.modal`), so
    the time error is zero. The spatial error is estimated from the ``refine`` ladder and the
    truncation of the Fourier series from the ``harmonics`` ladder, each by the observed order
    of its three finest levels (Roache's grid convergence index: ``1.25 |q_h - q_2h| /
    (2^p - 1)``, ``p`` at most 2); the modes left out of the largest harmonics (mode
    acceleration) add their measured share.
``time-step halving`` (plastic, contact, cut-outs)
    A reference FEM at three or more halvings of the time step on one mesh. Where the observed
    order of the three finest is within 0.5 of Newmark's 2, Richardson's extrapolation
    ``q_h + (q_h - q_2h) / 3`` is the truth and its uncertainty the change of that
    extrapolation from the coarser pair of levels; else the finest level is the truth and its
    uncertainty the difference of the two finest scaled by the observed order as above (with
    orders below 1, common here, the plain difference would understate the error). Finer
    meshes at the case's time step correct it to the finest (errors assumed additive), whose
    own uncertainty is the ladder's GCI, or the difference of two meshes in full.
``explicit`` (plastic, contact, cut-outs; the stored truths)
    The explicit reference (:mod:`reference_fem.explicit`: central differences at half the
    critical step, so the step halves with the mesh and the ladder's differences hold space
    and time together) over meshes r2, r4, r8. Richardson's extrapolation at the observed order
    of the three, ``q_8 + (q_8 - q_4) / (2^p - 1)``, is the truth where ``p`` is in
    :data:`EXTRAPOLATION_ORDERS` and the interleaved pair r3, r6, extrapolated at the same order,
    lands within less than the finest mesh's GCI of it;
    its uncertainty is 1.25 times the distance between the two extrapolations. Else the finest
    mesh is the truth and its GCI the uncertainty.

Uncertainties are relative max-norms over the window, in the measure the errors use (the
case's comparison window included). A probe the case lists under
``references['singular_probes']`` (a peak on a re-entrant corner) has no converged truth.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.optimize import brentq

from cases import get_case
from smfem.runs.files import jsonable
from smfem.runs.registry import lookup

from .cache import Run
from .jobs import OK, Job
from .metrics import common_grid, inside_window, smoothed
from .plan import (EXPLICIT, EXPLICIT_TRUTH, MODAL, MODAL_TRUTH, REF2D, REF3D, TIME_TRUTH, TruthPlan, explicit_truth,
                   full, quick)

#: order of Newmark's average-acceleration method
NEWMARK_ORDER = 2.0
#: an observed order this close to NEWMARK_ORDER lets Richardson extrapolate
ORDER_BAND = 0.5
#: the parts an uncertainty is the sum of
PARTS = ("time", "space", "harmonics", "modes")
#: Roache's safety factor for a three-level grid convergence index
GCI_SAFETY = 1.25
#: the observed orders Richardson may extrapolate at: below 0.5 the extrapolation would move the
#: finest level more than 2.4 times its last change (a ladder barely converging: the standard
#: element's plastic hinge in the notched strip, 0.08); above 4, the quadratic element's own
#: order and one more, the differences are round-off, not convergence
EXTRAPOLATION_ORDERS = (0.5, 4.0)


@dataclass
class Truth:
    """Converged probe histories of one case.

    Attributes
    ----------
    t : (n,) times, s
    values : probe -> (n,) history
    uncertainty : probe -> relative max-norm uncertainty; NaN: no converged truth (``notes``
        says why)
    parts : probe -> its parts (``time``, ``space``, ``harmonics``, ``modes``) and the
        observed orders
    levels : the runs it is made of (solver, settings, status, CPU time)
    key : for a stored truth, the key it was made for (:mod:`smfem.studies.stored`)
    calibration : probe -> the distance to a second, independent truth path and that path's
        uncertainty (:mod:`smfem.studies.calibration`); empty when not made
    source : where it came from: computed now, or stored (and where)
    """

    case: str
    method: str
    name: str
    t: np.ndarray
    values: dict
    uncertainty: dict
    parts: dict
    notes: dict
    levels: list
    cpu_time_s: float
    window: float = 0.0
    params: dict = field(default_factory=dict)
    key: str = ""
    calibration: dict = field(default_factory=dict)
    source: str = "computed"

    def uncertainty_of(self, probes) -> float:
        """The largest uncertainty over ``probes`` that have a converged truth (NaN if none)."""
        values = [self.uncertainty[p] for p in probes if p in self.uncertainty and math.isfinite(self.uncertainty[p])]
        return max(values) if values else math.nan

    def converged(self, probe: str) -> bool:
        return math.isfinite(self.uncertainty.get(probe, math.nan))

    def summary(self) -> dict:
        return {"case": self.case, "method": self.method, "name": self.name, "params": self.params,
                "uncertainty": self.uncertainty, "parts": self.parts, "notes": self.notes,
                "levels": self.levels, "cpu_time_s": self.cpu_time_s, "comparison_window_s": self.window,
                "end_time_s": float(self.t[-1]), **({"key": self.key} if self.key else {}),
                **({"calibration": self.calibration} if self.calibration else {})}

    def write(self, out: Path) -> None:
        """``history.csv`` (as ``smfem run`` writes it) and ``summary.json``."""
        out.mkdir(parents=True, exist_ok=True)
        pd.DataFrame({"t": self.t, **self.values}).to_csv(out / "history.csv", index=False, float_format="%.12g")
        (out / "summary.json").write_text(json.dumps(jsonable(self.summary()), indent=2))


# -- which truth ----------------------------------------------------------------------------
def modal_unsupported(case) -> str | None:
    """Why ``case`` has no modal truth (None if it has one)."""
    from reference_fem.harmonic import unsupported_reason

    return unsupported_reason(case)


def reference_solver(case) -> str:
    """The reference that can run ``case``: 2D where the scene has a 2D form, else 3D."""
    from cases.params import UnsupportedCase
    from reference_fem.mesh import build_mesh

    try:
        build_mesh(replace(case, params={**case.params, "dim": 2, "refine": 1}))
    except UnsupportedCase:
        return REF3D
    return REF2D


def explicit_unsupported(case) -> str | None:
    """Why the explicit reference cannot run ``case`` (None if it can)."""
    if case.wall is not None and case.material.plastic:
        return "contact with plasticity"
    if case.wall is not None and case.wall.friction > 0:
        return "a wall with friction"
    return None


def plan_for(name: str, base: dict, settings: str = "quick") -> TruthPlan:
    """The truth plan of case ``name`` with overrides ``base``: the study's own where it fits
    the case as set up; else modal where the case is linear and homogeneous along x3 (the
    unnotched elastic strip), else (a plastic variant cannot be modal) the explicit reference
    for ``full`` settings where it can run the case, time-step halving otherwise, on a
    reference that can run it (2D where the scene has a 2D form). A scene the plan does not
    have (from a file) is planned as a new one: the explicit ladder (quick: meshes 1, 2 and 4,
    1 and 2 in 3D) adapted so, its meshes times the scene's own ``refine``."""
    full_ = settings == "full"
    studies = {s.case: s for s in (*full(), *(() if full_ else quick()))}  # a scene only the full study has
    case = get_case(name, base)
    # a scene of the user's own: the explicit reference, fine in time whatever the scene's step
    # (meshes one step past the quick study's in 2D, two in 3D), adapted to its physics below
    solver = reference_solver(case)
    plan = studies[name].truth if name in studies else explicit_truth() if full_ else \
        explicit_truth(dict(refine=(1, 2, 4) if solver == REF2D else (1, 2)))
    modal_ok = not modal_unsupported(case)
    if plan.method != MODAL_TRUTH and modal_ok:
        plan = _modal_plan(case, full_)
    elif plan.method == MODAL_TRUTH and not modal_ok:
        plan = (explicit_truth() if full_ else
                TruthPlan(TIME_TRUTH, refine=(1, 2), dt_divisors=(1, 2, 4)))
    if plan.method == EXPLICIT_TRUTH and explicit_unsupported(case):
        plan = TruthPlan(TIME_TRUTH, refine=(2, 3) if full_ else (1, 2), dt_divisors=(1, 2, 4, 8) if full_ else (1, 2, 4))
    if plan.method == TIME_TRUTH:
        plan = replace(plan, solver=solver)
    if plan.method == EXPLICIT_TRUTH:
        plan = replace(plan, dim=lookup(solver).dim)
    scale = case.params.get("refine", 1)
    if name not in studies and scale != 1:  # the ladders start from the scene's own mesh
        plan = replace(plan, refine=tuple(scale * r for r in plan.refine), check=tuple(scale * r for r in plan.check))
    return plan


def _modal_plan(case, full_: bool) -> TruthPlan:
    """Meshes refine 1, 2, 4 (full: 2, 4, 8) and 1, 2, 4 (full: 2, 4, 8) times the case's
    harmonics (none for an axisymmetric case)."""
    scale = (2, 4, 8) if full_ else (1, 2, 4)
    return TruthPlan(MODAL_TRUTH, refine=scale,
                     harmonics=() if case.axisymmetric else tuple(k * case.harmonics for k in scale))


def jobs(name: str, plan: TruthPlan, base: dict) -> dict[tuple, Job]:
    """The runs a truth is made of, by role: ``('space', refine)``, ``('harmonics', n)``,
    ``('dt', divisor)``."""
    case = get_case(name, base)
    dt = case.dt
    out = {}
    if plan.method == EXPLICIT_TRUTH:
        sample = {"dt": dt / plan.output_divisor, "dim": plan.dim}
        options = dict(plan.options)
        return {(role, r): Job.make(name, plan.solver, {**base, **sample, "refine": r}, options=options)
                for role, levels in (("space", plan.refine), ("check", plan.check)) for r in levels}
    if plan.method == MODAL_TRUTH:
        n = plan.harmonics[-1] if plan.harmonics else case.harmonics
        sample = {"dt": dt / plan.output_divisor}
        for r in plan.refine:
            out["space", r] = Job.make(name, MODAL, {**base, **sample, "refine": r, "harmonics": n})
        for h in plan.harmonics:
            out["harmonics", h] = Job.make(name, MODAL, {**base, **sample, "refine": plan.refine[-1], "harmonics": h})
        return out
    coarse = plan.refine[0]
    for d in plan.dt_divisors:
        out["dt", d] = Job.make(name, plan.solver, {**base, "refine": coarse, **({"dt": dt / d} if d != 1 else {})})
    d = plan.space_dt_divisor
    for r in plan.refine[1:]:
        out["space", r] = Job.make(name, plan.solver, {**base, "refine": r, **({"dt": dt / d} if d != 1 else {})})
    return out


# -- sequences of levels --------------------------------------------------------------------
def _rel(d: np.ndarray, scale: np.ndarray, grid: np.ndarray, window: float) -> float:
    """``max |d| / max |scale|``, both seen through the comparison window where it fits whole
    (as :func:`smfem.runs.errors.history_errors` measures)."""
    keep = inside_window(grid, window)
    top = np.abs(smoothed(scale, grid, window)[keep]).max()
    return float(np.abs(smoothed(d, grid, window)[keep]).max() / top) if top else math.nan


def _on(run: Run, probe: str, grid: np.ndarray) -> np.ndarray:
    h = run.history
    return np.interp(grid, h["t"].to_numpy(), h[probe].to_numpy())


def _times(run: Run, end: float) -> np.ndarray:
    t = run.history["t"].to_numpy()
    return t[t <= end * (1 + 1e-12)]


def order_of(h, d_coarse: float, d_fine: float) -> float:
    """Observed order from three levels of mesh-size-like values ``h`` (coarse to fine, any
    ratios) and the differences of their consecutive results: negative where the differences
    grow, NaN where one is zero or no order in (0.05, 12) fits shrinking ones."""
    h1, h2, h3 = (float(x) for x in h)
    if not (d_coarse > 0 and d_fine > 0):
        return math.nan
    if math.isclose(h1 / h2, h2 / h3, rel_tol=1e-9) or d_fine >= d_coarse:
        return math.log(d_coarse / d_fine) / math.log(h2 / h3)  # exact for a constant ratio
    f = lambda p: (h1**p - h2**p) / (h2**p - h3**p) - d_coarse / d_fine
    lo, hi = 0.05, 12.0
    return brentq(f, lo, hi) if f(lo) * f(hi) < 0 else math.nan


def gci(d_coarse: float, d_fine: float, h=(4.0, 2.0, 1.0)) -> tuple[float, float]:
    """Uncertainty of the finest of three levels ``h`` (coarse to fine) and the observed order:
    ``1.25 d_fine / ((h2 / h3)^p - 1)``, ``p`` capped at 2; the plain difference ``d_fine``
    where the differences do not shrink or only two levels exist (``d_coarse`` NaN)."""
    p = order_of(h, d_coarse, d_fine) if math.isfinite(d_coarse) else math.nan
    if not math.isfinite(p) or p <= 0:
        return d_fine, p
    return GCI_SAFETY * d_fine / ((h[1] / h[2]) ** min(p, NEWMARK_ORDER) - 1), p


def _ladder(runs: list[Run], h, probe: str, grid: np.ndarray, window: float,
            scale: np.ndarray | None = None) -> tuple[float, float]:
    """GCI uncertainty and observed order of a ladder of runs (coarse to fine, mesh-size-like
    values ``h``) on one grid, relative to ``scale`` (default: the finest run)."""
    q = [_on(r, probe, grid) for r in runs[-3:]]
    if len(q) < 2:
        return 0.0, math.nan
    scale = q[-1] if scale is None else scale
    d_fine = _rel(q[-1] - q[-2], scale, grid, window)
    d_coarse = _rel(q[-2] - q[-3], scale, grid, window) if len(q) == 3 else math.nan
    return gci(d_coarse, d_fine, tuple(h[-3:]) if len(q) == 3 else (4.0, 2.0, 1.0))


def _not_ok(runs) -> list[str]:
    return [f"{r.job.describe()}: {r.status}" for r in runs if r.status != OK]


# -- assembling -----------------------------------------------------------------------------
def assemble(name: str, plan: TruthPlan, base: dict, runs: dict[tuple, Run]) -> Truth | None:
    """The truth from its runs (:func:`jobs`), or None if a run it needs has no history."""
    if any(not r.usable for r in runs.values()):
        return None
    case = get_case(name, base)
    window = case.references.get("comparison_window_s", 0.0)
    levels = [{"role": f"{k[0]} {k[1]}", "run": r.job.describe(), "status": r.status,
               "cpu_time_s": r.summary["cpu_time_s"]} for k, r in runs.items()]
    unique = {r.path: r for r in runs.values()}.values()  # one run may fill two roles
    cpu = float(sum(r.summary["cpu_time_s"] for r in unique))
    make = {MODAL_TRUTH: _modal, TIME_TRUTH: _time_halving, EXPLICIT_TRUTH: _explicit}[plan.method]
    t, values, parts, label = make(case, plan, runs, window)
    uncertainty, notes = {}, {}
    singular = case.references.get("singular_probes", {})
    for probe in case.probe_names:
        u = sum(parts[probe].get(k, 0.0) for k in PARTS)
        if probe in singular:
            uncertainty[probe], notes[probe] = math.nan, f"no converged truth: {singular[probe]}"
        elif not math.isfinite(u):
            uncertainty[probe], notes[probe] = math.nan, "no converged truth: the levels do not converge"
        else:
            uncertainty[probe] = u
    stopped = _not_ok(unique)
    if stopped:
        label += f"; covers t <= {t[-1]:.4g} s ({'; '.join(stopped)})"
    return Truth(case.name, plan.method, label, t, values, uncertainty, parts, notes, levels, cpu, window,
                 params=dict(case.params))


def _modal(case, plan, runs, window):
    space = [runs["space", r] for r in plan.refine]
    harm = [runs["harmonics", h] for h in plan.harmonics]
    finest = space[-1]
    grid = finest.history["t"].to_numpy()
    values, parts = {}, {}
    truncation = finest.summary["info"].get("truncation", {})
    sampling = finest.summary["info"].get("load_sampling", {})
    for probe in case.probe_names:
        values[probe] = finest.history[probe].to_numpy()
        u_s, p_s = _ladder(space, [1 / r for r in plan.refine], probe, grid, window)
        part = {"space": u_s, "order_space": p_s, "modes": float(truncation.get(probe, 0.0))}
        if sampling.get(probe, 0.0) > 0:  # a moving load sampled in time: its measured error (else exact)
            part["time"] = float(sampling[probe])
        if harm:
            part["harmonics"], part["order_harmonics"] = _ladder(harm, [1 / n for n in plan.harmonics], probe, grid, window)
        if math.isfinite(p_s) and p_s <= 0:
            part["space"] = math.nan  # finer meshes move the probe more: not converging
        parts[probe] = part
    p = finest.summary["params"]
    label = (f"{MODAL}: harmonic model r{p['refine']}" + (f" H{p['harmonics']}" if harm else "")
             + " exact in time (modal)")
    return grid, values, parts, label


def _time_halving(case, plan, runs, window):
    coarse, fine = plan.refine[0], plan.refine[-1]
    ladder = [runs["dt", d] for d in plan.dt_divisors]
    # at dt / space_dt_divisor, coarse to fine
    meshes = [runs["dt", plan.space_dt_divisor]] + [runs["space", r] for r in plan.refine[1:]]
    if any(b != 2 * a for a, b in zip(plan.dt_divisors, plan.dt_divisors[1:])):
        raise ValueError("the dt ladder must halve the time step at every level")
    end = min(r.history["t"].iloc[-1] for r in runs.values())
    qa, qb, qc = ladder[-3:]
    grid_a, grid_b, grid_0 = _times(qa, end), _times(qb, end), _times(meshes[0], end)
    values, parts = {}, {}
    for probe in case.probe_names:
        a_, b_, c_ = (_on(r, probe, grid_a) for r in (qa, qb, qc))
        d1, d2 = _rel(b_ - a_, c_, grid_a, window), _rel(c_ - b_, c_, grid_a, window)
        p = order_of((4.0, 2.0, 1.0), d1, d2)
        b, c = _on(qb, probe, grid_b), _on(qc, probe, grid_b)
        if math.isfinite(p) and abs(p - NEWMARK_ORDER) <= ORDER_BAND:
            factor = 1.0 / (2**NEWMARK_ORDER - 1)
            T = c + (c - b) * factor
            T_coarse = b_ + (b_ - a_) * factor
            u_t = _rel(np.interp(grid_a, grid_b, T) - T_coarse, T_coarse, grid_a, window)
            how = "Richardson"
        else:  # the difference of the two finest, scaled by the observed order (GCI)
            T = c
            d_fine = _rel(c - b, c, grid_b, window)
            u_t = GCI_SAFETY * d_fine / (2 ** min(p, NEWMARK_ORDER) - 1) if math.isfinite(p) and p > 0 else d_fine
            how = "finest"
        # the finest mesh (at the meshes' dt): its difference corrects the ladder's mesh
        delta = _on(meshes[-1], probe, grid_0) - _on(meshes[0], probe, grid_0)
        T = T + np.interp(grid_b, grid_0, delta)
        u_s, p_s = _ladder(meshes, [1 / r for r in plan.refine], probe, grid_0, window,
                           scale=np.interp(grid_0, grid_b, T))
        values[probe] = T
        parts[probe] = {"time": u_t, "order_time": p, "time_estimate": how, "space": u_s, "order_space": p_s}
    p_ = ladder[0].summary["params"]
    label = (f"{plan.solver} r{coarse} at dt/{', dt/'.join(map(str, plan.dt_divisors))} (dt = {p_['dt']:g} s), "
             f"Richardson where the order is near 2, corrected to r{fine} at "
             + ("dt" if plan.space_dt_divisor == 1 else f"dt/{plan.space_dt_divisor}")
             + (f" (meshes r{', r'.join(map(str, plan.refine))})" if len(plan.refine) > 2 else ""))
    return grid_b, values, parts, label


def _explicit(case, plan, runs, window):
    """Richardson's extrapolation of the explicit ladder's three finest meshes, checked by the
    interleaved pair; else the finest mesh with its grid convergence index (module doc).

    The step is a fixed fraction of the critical one, so it halves with the mesh: the
    ladder's differences hold the time error too, and its order is that of both together."""
    space = [runs["space", r] for r in plan.refine]
    check = [runs["check", r] for r in plan.check]
    finest = space[-1]
    grid = finest.history["t"].to_numpy()
    values, parts = {}, {}
    for probe in case.probe_names:
        q = [_on(r, probe, grid) for r in space]
        u_fine, p = _ladder(space, [1 / r for r in plan.refine], probe, grid, window)
        part = {"order_space": p, "space": u_fine, "estimate": "finest"}
        values[probe] = q[-1]
        if len(q) >= 3 and check and EXTRAPOLATION_ORDERS[0] <= p <= EXTRAPOLATION_ORDERS[1]:
            factor = 1.0 / (2**p - 1)
            extrapolated = q[-1] + (q[-1] - q[-2]) * factor
            c = [_on(r, probe, grid) for r in check]
            other = c[1] + (c[1] - c[0]) * factor
            u_rich = GCI_SAFETY * _rel(extrapolated - other, extrapolated, grid, window)
            if u_rich < u_fine:
                values[probe] = extrapolated
                part.update(space=u_rich, space_finest=u_fine, estimate="Richardson",
                            extrapolation=_rel(extrapolated - q[-1], extrapolated, grid, window))
        if math.isfinite(p) and p <= 0:
            part["space"] = math.nan  # finer meshes move the probe more: not converging
        parts[probe] = part
    p_ = finest.summary["params"]
    options = "".join(f", {k} {v}" for k, v in plan.options)
    label = (f"{EXPLICIT}: r{p_['refine']} ({plan.dim}D{options}), central differences at "
             f"{finest.summary['info'].get('safety', 0.5):g} of the critical step, meshes "
             f"r{', r'.join(map(str, plan.refine))}"
             + (f", Richardson where the r{plan.check[0]}-r{plan.check[1]} pair confirms it" if check else ""))
    return grid, values, parts, label
