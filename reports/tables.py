"""The report's tables as DataFrames, and ``tables/*.csv``."""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from . import metrics
from .analysis import HEADLINE_MEASURE, CaseAnalysis
from .jobs import OK
from .plan import SMFEM


def runs_table(analyses: list[CaseAnalysis]) -> pd.DataFrame:
    """Every run: what it was, how it ended, its size and cost."""
    rows = []
    for an in analyses:
        tagged = [(s, "series", r) for s, runs in an.runs.series.items() for r in runs]
        for solver, role, run in tagged + [(an.runs.reference.job.solver, "reference", an.runs.reference)]:
            s = run.summary or {}
            rows.append({"case": an.case.name, "solver": solver, "role": role, "level": run.label,
                         "status": run.status, "n_dof": s.get("n_dof"), "n_steps": s.get("n_steps"),
                         "cpu_time_s": s.get("cpu_time_s"), "wall_time_s": s.get("wall_time_s"),
                         "iterations_mean": (s.get("iterations") or {}).get("mean"),
                         "iterations_max": (s.get("iterations") or {}).get("max"),
                         "message": run.message, "directory": str(run.path or "")})
    return pd.DataFrame(rows)


def headline_table(analyses: list[CaseAnalysis], tol: float = metrics.TOLERANCE) -> pd.DataFrame:
    """Per case and solver: the reference, the best error, the CPU time to reach ``tol`` and
    SMFEM's speed-up over that solver (CPU time to ``tol`` of the solver over SMFEM's)."""
    rows = []
    for an in analyses:
        mine = an.solvers.get(SMFEM)
        for solver, s in an.solvers.items():
            available = s.status == OK and an.reference is not None
            if s.status != OK:
                cost = f"not available: {s.message}"
            else:
                cost = s.cost.text() if an.reference is not None else "no reference"
            speed = ""
            if available and mine is not None and solver != SMFEM:
                speed = metrics.speedup(s.cost, mine.cost) if mine.status == OK else "n/a"
            rows.append({
                "case": an.case.name, "solver": solver,
                "reference": an.reference.name if an.reference is not None else "none available",
                "levels": len(s.cpu),
                "best_error_pct": 100 * s.cost.best if available else math.nan,
                f"cpu_s_to_{100 * tol:g}pct": cost,
                "smfem_speedup": speed,
            })
    return pd.DataFrame(rows)


def write_tables(analyses: list[CaseAnalysis], out: Path) -> dict[str, pd.DataFrame]:
    """Write ``out/*.csv`` and return the tables by name."""
    out.mkdir(parents=True, exist_ok=True)
    tables = {
        "headline": headline_table(analyses),
        "runs": runs_table(analyses),
        "errors": pd.concat([an.errors for an in analyses], ignore_index=True),
        "orders": pd.concat([an.orders for an in analyses], ignore_index=True),
        "richardson": pd.concat([an.richardson for an in analyses], ignore_index=True),
        "published": pd.concat([an.published for an in analyses], ignore_index=True),
    }
    for name, table in tables.items():
        table.to_csv(out / f"{name}.csv", index=False, float_format="%.6g")
    (out / "README.txt").write_text(
        "headline.csv: CPU time (s) to reach 1 % error, per case and solver, and SMFEM's speed-up\n"
        f"  error measure: {HEADLINE_MEASURE}\n"
        "errors.csv: per run and probe, relative max-norm and L2 errors against the named reference\n"
        "orders.csv: observed orders of convergence (log-log fit of error against h)\n"
        "richardson.csv: Richardson extrapolation of each probe's peak from the three finest levels\n"
        "published.csv: extrema found near published extrema\n"
        "runs.csv: every run, its status, size and cost\n")
    return tables
