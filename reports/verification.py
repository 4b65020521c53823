"""Code verification: each solver's observed orders on the manufactured motions.

Solution verification (the truths) says how far a run is from the answer; code verification
says whether each solver solves the equations it claims to, at the order its discretization
has (ASME V&V 10/20; Roache; Salari & Knupp). On the manufactured ring and prism
(:mod:`cases.verification`, exact motion known, material varying along x3) it measures:

- space: the relative L2 error of the displacement over the body (each solver's own norm,
  ``info['error_l2']``) on successively refined meshes, harmonics resolved, with the motion's
  time function ``t^2``, which Newmark's scheme integrates exactly (the step leaves the mesh's
  error alone, so five long steps do); the order of the finest pair against the element's in
  L2: SMFEM's bilinear moment-scheme element 2, the reference's quadratic element 3;
- time: successive halvings of the step at a fixed mesh (time function ``1 - cos 3t``), the
  differences of each displacement probe's end value (the mesh's own error cancels), against
  Newmark's 2;
- harmonics (SMFEM): the L2 error with fewer harmonics than the motion holds against the error
  with all of them and with twice as many: once all are in, it is the mesh's.

A single node's value would do for neither solver's space order: the reference's nodes
superconverge (orders 3.9-6.1 at refine 1-4, asymptotic only past what a quick check affords).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from cases import verification
from cases.geometry import PRISM, RING
from smfem.runs.registry import REF3D, SMFEM, lookup, solve

#: the order each solver's scheme has in each parameter, for the table (space: in L2)
THEORY = {(SMFEM, "space"): 2.0, (SMFEM, "time"): 2.0, (REF3D, "space"): 3.0, (REF3D, "time"): 2.0}
#: how far an observed order may be from the theory's
ORDER_TOLERANCE = 0.2
PROBES = ("u1", "u2", "u3")
#: the measure of the space and harmonics ladders
L2 = "L2"
#: the space and harmonics ladders' window: five steps of t^2, exact in time
EXACT_IN_TIME = {"time": "quadratic", "t_end": 0.25, "dt": 0.05}


@dataclass(frozen=True)
class Ladder:
    """One measured order: a solver, a body, a parameter and its levels (settings over the
    manufactured scene's defaults)."""

    solver: str
    body: str
    parameter: str
    levels: tuple[dict, ...]
    base: dict


def plan(quick: bool = True) -> tuple[Ladder, ...]:
    """The ladders of ``smfem verify``: quick (about a minute on two cores) or full."""
    space = (1, 2, 4) if quick else (1, 2, 4, 8)
    ladders = []
    for body in (PRISM, RING):
        ladders += [
            Ladder(SMFEM, body, "space", tuple({"refine": r} for r in space), {**EXACT_IN_TIME, "harmonics": 6}),
            Ladder(SMFEM, body, "time", tuple({"dt": d} for d in (0.05, 0.025, 0.0125)), {"refine": 2, "harmonics": 4}),
            Ladder(SMFEM, body, "harmonics", tuple({"harmonics": h} for h in ((3, 4, 8) if body == RING else (2, 3, 6))),
                   {**EXACT_IN_TIME, "refine": 2}),
        ]
    # the reference in 3D: its section is 2 x 2 elements at refine 1; the prism's x3 elements
    # (as long as the section's) are pre-asymptotic there for its third harmonic, so it goes
    # to refine 4 (21,375 dof, 7 s); the ring's 64 elements around resolve its harmonics, and
    # its refine 2 (37,632 dof, 10 s) is as far as a quick check goes
    ladders += [
        Ladder(REF3D, PRISM, "space", tuple({"refine": r} for r in (1, 2, 4)), EXACT_IN_TIME),
        Ladder(REF3D, RING, "space", ({"refine": 1}, {"refine": 2}), EXACT_IN_TIME),
        Ladder(REF3D, PRISM, "time", tuple({"dt": d} for d in (0.05, 0.025, 0.0125)), {"refine": 1}),
        Ladder(REF3D, RING, "time", tuple({"dt": d} for d in (0.05, 0.025, 0.0125)), {"refine": 1}),
    ]
    return tuple(ladders)


def run_level(ladder: Ladder, level: dict) -> dict:
    """One level: the L2 error at the end, per probe its error against the exact motion and its
    end value, and the CPU."""
    # the parameters the solver's name fixes (the 3D reference's dim, the quadratic element)
    case = verification.build(ladder.body, {**ladder.base, **level, **lookup(ladder.solver).fixed})
    result = solve(ladder.solver, case)
    if not result.converged:
        raise RuntimeError(f"{case.name} ({ladder.solver}, {level}): {result.message}")
    exact = verification.exact(case, result.t)
    return {"errors": {p: float(np.abs(result.history[p] - exact[p]).max() / np.abs(exact[p]).max()) for p in PROBES}
            | {L2: float(result.info["error_l2"])},
            "ends": {p: float(result.history[p][-1]) for p in PROBES}, "cpu_s": float(result.cpu_time_s),
            "n_dof": int(result.n_dof)}


def measure(ladder: Ladder, runs: list[dict]) -> list[dict]:
    """Rows of ``orders.csv`` for one ladder: the L2 error's (space, harmonics) or each probe's
    (time), with the observed order of the finest pair and the theory's (harmonics: the floor
    check)."""
    rows = []
    for p in (PROBES if ladder.parameter == "time" else (L2,)):
        errors = [r["errors"][p] for r in runs]
        row = {"solver": ladder.solver, "body": ladder.body, "parameter": ladder.parameter, "probe": p,
               "levels": " ".join(_label(lv) for lv in ladder.levels), "errors": " ".join(f"{e:.3g}" for e in errors),
               "cpu_s": sum(r["cpu_s"] for r in runs)}
        if ladder.parameter == "space":
            observed, theory = math.log2(errors[-2] / errors[-1]), THEORY[(ladder.solver, "space")]
        elif ladder.parameter == "time":
            d = [abs(a["ends"][p] - b["ends"][p]) for a, b in zip(runs[:-1], runs[1:])]
            row["differences"] = " ".join(f"{x:.3g}" for x in d)
            observed, theory = math.log2(d[-2] / d[-1]), THEORY[(ladder.solver, "time")]
        else:  # harmonics: too few, all the motion holds, twice as many
            observed, theory = math.nan, math.nan
            row["too_few_over_all"] = errors[0] / errors[1]
        # harmonics: once all are in, more change nothing but round-off (the mesh's error stays)
        within = (abs(observed - theory) <= ORDER_TOLERANCE if theory == theory
                  else abs(errors[1] - errors[2]) <= 0.1 * errors[1])
        row.update(observed_order=observed, theoretical_order=theory, within=bool(within))
        rows.append(row)
    return rows


def _label(level: dict) -> str:
    return " ".join(f"{k}={v:g}" for k, v in level.items())


def verify(quick: bool = True, progress=None) -> pd.DataFrame:
    """Run every ladder of :func:`plan` and return ``orders.csv``'s table."""
    rows = []
    ladders = plan(quick)
    for i, ladder in enumerate(ladders):
        rows += measure(ladder, [run_level(ladder, level) for level in ladder.levels])
        if progress:
            progress(i + 1, len(ladders))
    return pd.DataFrame(rows)


def write(table: pd.DataFrame, out: Path, csv: str = "orders.csv") -> list[Path]:
    """``out/orders.csv`` (the report: ``tables/code_verification.csv``) and
    ``out/figures/verification-SOLVER.png``; returns the figures."""
    from .figures import verification_orders

    (out / "figures").mkdir(parents=True, exist_ok=True)
    (out / csv).parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(out / csv, index=False, float_format="%.4g")
    return [verification_orders(table, solver, out / "figures" / f"verification-{solver}.png")
            for solver in table.solver.unique()]


def cached(cache_dir: Path, quick: bool) -> pd.DataFrame:
    """:func:`verify`'s table, kept beside the report's runs by both solvers' code versions (a
    rebuilt report runs nothing new)."""
    from smfem.studies.cache import code_version

    path = cache_dir / f"code-verification-{'quick' if quick else 'full'}-{code_version(SMFEM)}-{code_version('reference')}.csv"
    if not path.exists():
        cache_dir.mkdir(parents=True, exist_ok=True)
        verify(quick).to_csv(path, index=False)
    return pd.read_csv(path)


def summary(table: pd.DataFrame) -> list[str]:
    """One line per solver, body and parameter (what ``smfem verify`` prints)."""
    lines = []
    for (solver, body, parameter), rows in table.groupby(["solver", "body", "parameter"], sort=False):
        if parameter == "harmonics":
            what = f"error at the spatial floor once all the motion's harmonics are in: {'yes' if rows.within.all() else 'no'}"
        else:
            lo, hi = rows.observed_order.min(), rows.observed_order.max()
            measure = "of the L2 error " if parameter == "space" else ""
            what = (f"observed order {measure}{lo:.2f}{'' if lo == hi else f'-{hi:.2f}'} "
                    f"(theory {rows.theoretical_order.iloc[0]:g})")
        lines.append(f"{solver} {body} {parameter}: {what}{'' if rows.within.all() else ' (off by more than 0.2)'}")
    return lines
