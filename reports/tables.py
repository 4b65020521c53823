"""The report's tables as DataFrames, and ``tables/*.csv``."""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from smfem.runs.estimate import headline
from smfem.runs.registry import lookup

from smfem.studies import metrics
from .analysis import FAMILIES, HEADLINE_MEASURE, CaseAnalysis
from .timing import COLUMNS as TIMING_COLUMNS
from .timing import speedup_range
from smfem.studies.calibration import FLOOR, SHARPNESS
from smfem.studies.calibration import table as calibration_table
from smfem.studies.effectivity import BAND
from smfem.studies.jobs import NOT_INSTALLED, OK
from smfem.studies.plan import SMFEM
from smfem.studies.timing import TimingRule
from smfem.studies.truth import PARTS


def pct_label(target: float) -> str:
    """A target's suffix in the headline's column names: 0.01 -> '1pct'."""
    return f"{100 * target:g}pct"


#: the timing pass's rule as tables/README.txt states it (the budget is an option)
RULE = TimingRule()
#: the suffix of a speed-up's column that holds its range over the timing pass's repeats
RANGE = "_range"


def runs_table(analyses: list[CaseAnalysis]) -> pd.DataFrame:
    """Every run: what it was for, how it ended, its size and cost."""
    rows = []
    for an in analyses:
        tagged = [(s, "series", r) for s, runs in an.runs.series.items() for r in runs]
        if an.runs.reference is not None:
            tagged.append((an.runs.reference.job.solver, "same-dt reference", an.runs.reference))
        tagged += [(r.job.solver, f"truth: {role[0]} {role[1]}", r) for role, r in an.runs.truth_runs.items()]
        estimated = _estimated_errors(an)
        for solver, role, run in tagged:
            s = run.summary or {}
            rows.append({"case": an.case.name, "solver": solver, "role": role, "level": run.label,
                         "status": run.status, "n_dof": s.get("n_dof"), "n_steps": s.get("n_steps"),
                         "cpu_time_s": s.get("cpu_time_s"), "wall_time_s": s.get("wall_time_s"),
                         "peak_memory_mb": s.get("peak_memory_mb"),
                         "iterations_mean": (s.get("iterations") or {}).get("mean"),
                         "iterations_max": (s.get("iterations") or {}).get("max"),
                         "inside_model": inside_model(s.get("validity")),
                         "estimated_error": estimated.get(run.path, math.nan),
                         "message": run.message, "directory": str(run.path or "")})
    return pd.DataFrame(rows)


def _estimated_errors(an: CaseAnalysis) -> dict:
    """Per estimated run's directory: its estimated error in the headline measure (the largest
    over its displacement and velocity probes)."""
    return {run.path: top[1] for run, est in an.runs.estimates.values() if (top := headline(an.case, est))}


def effectivity_table(analyses: list[CaseAnalysis]) -> pd.DataFrame:
    """Every measured estimate against the truth (:mod:`smfem.studies.effectivity`)."""
    frames = [an.effectivity for an in analyses if len(an.effectivity)]
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()


#: the run parameters that place a run on a work-precision front
SETTINGS = ("refine", "coarsen", "harmonics", "dt", "dim", "element", "time_scheme")


def fronts_table(analyses: list[CaseAnalysis]) -> pd.DataFrame:
    """Every run with a total error: its settings, CPU, headline error against the truth, whether
    it is on its solver's front, and the key of the truth it was measured against (what
    ``smfem run --tol`` starts from, :func:`smfem.studies.stored.write_fronts`)."""
    rows = []
    for an in analyses:
        key = an.truth.key if an.truth is not None else ""
        for solver, s in an.solvers.items():
            if s.status != OK or not len(s.points):
                continue
            params = {r.label: r.summary["params"] for r in an.runs.series[solver] if r.status == OK}
            for p in s.points.itertuples():
                rows.append({"case": an.case.name, "solver": solver, "level": p.label,
                             **{k: params[p.label].get(k) for k in SETTINGS}, "n_dof": p.n_dof, "cpu_s": p.cpu,
                             "total": p.total, "on_front": p.label in s.front, "truth_key": key})
    return pd.DataFrame(rows)


def inside_model(validity: dict | None) -> str:
    """``yes``, or what leaves the small-strain model (smfem.runs.validity), for the runs table."""
    if not validity:
        return ""
    if validity.get("valid"):
        return "yes"
    return "no: " + ", ".join(f"{k} {validity[k]:.3g}" for k in validity.get("exceeded", ()))


def _cost_columns(an: CaseAnalysis, solver: str, s, costs: dict, mine: dict | None,
                  no_truth: str | None = None) -> dict:
    """CPU time to each target (with its settings) and SMFEM's speed-up there (against
    ``mine``, SMFEM's best element at each target; none on SMFEM's own rows), beside it its range
    over the timing pass's repeats (:func:`reports.timing.speedup_range`, where both sides were
    timed); ``no_truth``: why the probes have no truth although the case has one."""
    row = {}
    for k, (target, cost) in enumerate(costs.items()):
        if s.status != OK:  # the reason once, in the first target's cell, without the solver's name
            text = f"not available: {s.message.removeprefix(f'{solver}: ')}" if k == 0 else "not available"
        elif an.truth is None or no_truth:
            text = no_truth or "no truth"
        else:
            text = cost.text()
        row[f"cpu_s_to_{pct_label(target)}"] = text
    for target, cost in costs.items():
        speed = ""
        if lookup(solver).family != SMFEM and s.status == OK and mine is not None:
            speed = metrics.speedup(cost, mine[target])
        row[f"smfem_speedup_{pct_label(target)}"] = speed
        row[f"smfem_speedup_{pct_label(target)}{RANGE}"] = speedup_range(an, solver, target, cost, mine[target]) if speed else ""
    return row


def headline_table(analyses: list[CaseAnalysis]) -> pd.DataFrame:
    """Per case and solver: the truth and its uncertainty, the best total error, the CPU time
    (and settings) of the cheapest run reaching each target, and SMFEM's speed-up there; the
    series of one solver's procedures (CalculiX's) or engines (the 3D reference's implicit and
    explicit) one row, at each target the cheapest, named in the cell
    (:meth:`reports.analysis.CaseAnalysis.competitors`)."""
    rows = []
    for an in analyses:
        mine = an.smfem_costs()
        truth = an.truth.name if an.truth is not None else "none available"
        # CalculiX's procedures one row, the 3D engines one; a solver not installed is named in the case's section
        for solver, s in an.competitors().items():
            row = {"case": an.case.name, "solver": solver, "truth": truth,
                   "truth_uncertainty_pct": 100 * an.truth_uncertainty, "runs": len(s.points),
                   "best_error_pct": 100 * s.points.total.min() if s.status == OK and len(s.points) else math.nan}
            rows.append(row | _cost_columns(an, solver, s, s.costs, mine))
    return pd.DataFrame(rows)


def families_table(analyses: list[CaseAnalysis]) -> pd.DataFrame:
    """The headline's columns for the probes outside it (:data:`reports.analysis.FAMILIES`:
    stresses, plastic strains), each with its own targets, per case that has such probes."""
    rows = []
    for an in analyses:
        for family in FAMILIES:
            probes = an.probes_of(family)
            if not probes:
                continue
            mine = an.smfem_costs(family)
            u = an.uncertainty_of(family)
            no_truth = None if math.isfinite(u) else "no converged truth: singular probes (truth.csv says why)"
            for solver, s in an.solvers.items():
                if s.status == NOT_INSTALLED:
                    continue
                errors = s.points[family] if s.status == OK and len(s.points) else pd.Series(dtype=float)
                row = {"case": an.case.name, "family": family, "probes": " ".join(probes), "solver": solver,
                       "truth_uncertainty_pct": 100 * u,
                       "best_error_pct": 100 * errors.min() if errors.notna().any() else math.nan}
                rows.append(row | _cost_columns(an, solver, s, s.family_costs[family], mine, no_truth))
    return pd.DataFrame(rows)


def spatial_table(analyses: list[CaseAnalysis]) -> pd.DataFrame:
    """The paper's comparison: runs at the case's time step against the finest reference run
    at that time step (the spatial discretization only)."""
    rows = []
    for an in analyses:
        for solver, s in an.solvers.items():
            if s.status != OK or not len(s.points):
                continue
            for p in s.points[s.points.spatial.notna()].itertuples():
                rows.append({"case": an.case.name, "solver": solver, "level": p.label, "n_dof": p.n_dof,
                             "cpu_time_s": p.cpu, "reference": an.reference.name if an.reference else "",
                             "spatial_error_pct": 100 * p.spatial, "total_error_pct": 100 * p.total})
    return pd.DataFrame(rows)


def truth_table(analyses: list[CaseAnalysis]) -> pd.DataFrame:
    """Per case and probe: how the truth was made and how exact it is."""
    rows = []
    for an in analyses:
        t = an.truth
        if t is None:
            continue
        for probe in an.case.probe_names:
            parts = t.parts.get(probe, {})
            rows.append({"case": an.case.name, "probe": probe, "method": t.method, "truth": t.name,
                         "source": t.source, "uncertainty_pct": 100 * t.uncertainty[probe],
                         **{f"{k}_pct": 100 * parts[k] for k in PARTS if k in parts},
                         **{k: v for k, v in parts.items() if k.startswith("order") or k.endswith("estimate")},
                         "note": t.notes.get(probe, ""), "cpu_time_s": t.cpu_time_s})
    return pd.DataFrame(rows)


def carried_table(analyses: list[CaseAnalysis]) -> pd.DataFrame:
    """Per carried series (:mod:`smfem.studies.ladder`): how far it climbed and why it stopped."""
    rows = [{"case": an.case.name, "solver": solver, "runs": len(an.runs.series.get(solver, [])),
             "levels": len(next(s.levels for s in an.runs.study.series if s.solver == solver)), "outcome": outcome}
            for an in analyses for solver, outcome in an.runs.carried.items()]
    return pd.DataFrame(rows, columns=["case", "solver", "runs", "levels", "outcome"])


def write_tables(analyses: list[CaseAnalysis], out: Path, timing: pd.DataFrame | None = None) -> dict[str, pd.DataFrame]:
    """Write ``out/*.csv`` and return the tables by name; ``timing``: the timing pass's rows
    (:func:`reports.timing.time_headline`, already in the analyses' costs; None: no pass)."""
    out.mkdir(parents=True, exist_ok=True)
    tables = {
        "headline": headline_table(analyses),
        "stresses": families_table(analyses),
        "truth": truth_table(analyses),
        "calibration": calibration_table({an.case.name: an.truth for an in analyses if an.truth is not None}),
        "spatial": spatial_table(analyses),
        "runs": runs_table(analyses),
        "errors": pd.concat([an.errors for an in analyses], ignore_index=True),
        "orders": pd.concat([an.orders for an in analyses], ignore_index=True),
        "published": pd.concat([an.published for an in analyses], ignore_index=True),
        "effectivity": effectivity_table(analyses),
        "fronts": fronts_table(analyses),
        "carried": carried_table(analyses),
        "timing": pd.DataFrame(columns=TIMING_COLUMNS) if timing is None else timing,
    }
    for name, table in tables.items():
        table.to_csv(out / f"{name}.csv", index=False, float_format="%.6g")
    targets = " and ".join(f"{100 * t:g} %" for t in metrics.TARGETS)
    (out / "README.txt").write_text(
        f"headline.csv: per case and solver, CPU time (s) of the cheapest run within {targets} total error\n"
        "  against the case's truth, its settings, and SMFEM's speed-up (calculix: the cheapest of its\n"
        "  procedures at each target, named in the cell; reference-3d: the cheaper of its implicit and explicit\n"
        "  engines, named so; fronts.csv has each procedure's and engine's runs); each CPU time\n"
        "  of a run within the target is the minimum over the timing pass's repeats (timing.csv), each speed-up a\n"
        "  ratio of minima, and smfem_speedup_*_range its range over the repeats (the other's fastest over\n"
        "  SMFEM's slowest to the other's slowest over SMFEM's fastest); a bound (> x) keeps the study's single\n"
        "  shot of the dearest run\n"
        f"  error measure: {HEADLINE_MEASURE}\n"
        "stresses.csv: the same for the stress and plastic-strain probes (family), each family with its own\n"
        f"  targets ({'; '.join(f'{f}: ' + ' and '.join(f'{100 * t:g} %' for t in ts) for f, (_, ts) in FAMILIES.items())})\n"
        "truth.csv: per case and probe, how the truth was made, where it came from (stored or computed)\n"
        "  and its uncertainty (relative max-norm)\n"
        "calibration.csv: per stored truth and probe, the distance to a second, independent truth path and\n"
        f"  both uncertainties (covered: distance <= u + u2; sharp: u <= {SHARPNESS:g} max(distance, "
        f"{100 * FLOOR:.3g} %)); widened: the truth's own uncertainty did not cover the distance and is\n"
        "  stated as distance + u2 (its own estimate in summary.json, own_uncertainty)\n"
        "spatial.csv: runs at the case's time step against the finest reference run at that time step\n"
        "errors.csv: per run and probe, relative max-norm and L2 errors (kind: total, spatial, published)\n"
        "orders.csv: observed orders (log-log fit of the headline measure against dt or the mesh);\n"
        "  reading: what an order below 0.5 or negative means\n"
        "published.csv: extrema found near published extrema\n"
        "runs.csv: every run (series, same-dt reference, truth levels), its status, size and cost (peak_memory_mb:\n"
        "  the worker's resident high-water mark during the run, smfem.runs.memory), and inside_model: yes, or which\n"
        "  small-strain limit it passes (smfem.runs.validity);\n"
        "  estimated_error: the run's own error estimate (smfem.runs.estimate), where the study measured it\n"
        "effectivity.csv: per solver, setting (defaults, refine 2, dt/2) and displacement or velocity probe, the\n"
        "  run's error estimate and its parts, its actual error against the truth and effectivity = estimate /\n"
        f"  actual (where the actual error exceeds {metrics.TRUTH_MARGIN:g} truth uncertainties); honest within "
        f"[{BAND[0]:g}, {BAND[1]:g}]\n"
        "fronts.csv: per run with a total error, its settings (refine, coarsen, harmonics, dt, dim, element,\n  time_scheme), CPU, total\n"
        "  error (headline measure), on_front and the key of the truth it was measured against; smfem report\n"
        "  --store-fronts keeps it with the stored truths (smfem/truths/CASE/front.csv), where smfem run --tol starts\n"
        "carried.csv: per series carried along its ladder to a target or a CPU budget (the full report's):\n"
        "  the runs it made of its levels and where it stopped, and why\n"
        "timing.csv: the timing pass: per case, solver and target, the run behind its headline CPU time (label),\n"
        "  timed again one at a time with nothing else running, SMFEM's and the others' by turns, until it has\n"
        f"  {RULE.repeats} repeats and {RULE.total_s:g} CPU s in all (a full report's and a retime's: also\n"
        f"  {RULE.settle_s:g} CPU s and {RULE.settle_repeats} repeats or {RULE.max_repeats} repeats, spread over"
        f" {RULE.sweeps} sweeps,\n  and a second repeat within {100 * RULE.hold:g} % of the least;"
        f" a run over {RULE.long_s:g} s:\n  once, twice within the pass's budget): repeats,\n"
        "  cpu_min_s (the headline's), cpu_median_s, cpu_max_s and study_cpu_s (the study's single shot, as\n"
        "  runs.csv and fronts.csv keep it); smfem report --retime makes it again\n"
        "timing_repeats.csv: every repeat of that pass in the order taken (case, solver, label, batch, repeat,\n"
        "  cpu_s) and when its batch ended (UTC): how the host's speed moved during the pass\n")
    return tables
