"""The 3D reference's explicit engine against the stored truths, beside its implicit engine: the
full plan's explicit 3D series, each run with the error and CPU time the report would give it.

    python benchmarks/explicit_3d.py [--budget S] [--fronts CSV] [--tiny] [SCENE ...]

Per scene of the full plan with an explicit 3D series (``smfem.studies.plan.full``: its levels
and options, meshes with B-bar on the notched scenes), the levels run cheapest first as the
study's carried series does (``smfem.studies.ladder.work``, the Courant steps counted); the
ladder stops at 1 % (the headline target), or before a run whose predicted CPU time passes
``--budget`` (default 300 s). One line per run: level, headline error against the stored truth
(``smfem.studies.metrics.headline_error``), CPU time, unknowns, the engine's step and steps. Then
the implicit engine's cheapest run within 1 % and 5 % in ``--fronts`` (default the published
full report's ``tables/fronts.csv``), for the side by side. ``--tiny``: the thick cylinder's
first level over five of its steps.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import pandas as pd

from cases import get_case
from smfem.api import truth as stored_truth
from smfem.runs.registry import REF3D, REF3D_EXPLICIT, lookup, solve, with_fixed
from smfem.studies.ladder import work
from smfem.studies.metrics import headline_error
from smfem.studies.plan import full

FRONTS = Path(__file__).resolve().parents[1] / "docs" / "full-report" / "tables" / "fronts.csv"
TARGETS = (0.01, 0.05)


def measure(name: str, levels, options: dict, budget: float, base: dict | None = None) -> None:
    truth = stored_truth(name)
    print(f"\n{name}: explicit 3D{' ' + str(options) if options else ''}", flush=True)
    courant = lookup(REF3D_EXPLICIT).courant
    params = [with_fixed(REF3D_EXPLICIT, get_case(name, {**(base or {}), **level})).params for level in levels]
    last = None
    for level, p in sorted(zip(levels, params), key=lambda lp: work(lp[1], False, courant)):
        if last is not None:
            predicted = last[0] * work(p, False, courant) / work(last[1], False, courant)
            if predicted > budget:
                print(f"  {_level(level):10s} skipped: predicted {predicted:.3g} CPU s > {budget:g}", flush=True)
                break
        case = get_case(name, {**(base or {}), **level})
        run = solve(REF3D_EXPLICIT, case, options=options)
        error = headline_error(with_fixed(REF3D_EXPLICIT, case), truth, run.t, run.history)
        print(f"  {_level(level):10s} error {100 * error:7.3g} %  CPU {run.cpu_time_s:8.3g} s  unknowns {run.n_dof:7d}  "
              f"step {run.info['time_step']:.3g} s x {run.info['steps']}", flush=True)
        last = (run.cpu_time_s, p)
        if error <= TARGETS[0]:
            break


def implicit(name: str, fronts: pd.DataFrame) -> None:
    """The implicit 3D engine's cheapest run within each target in ``fronts``."""
    mine = fronts[(fronts.case == name) & (fronts.solver == REF3D)]
    for target in TARGETS:
        within = mine[mine.total <= target].sort_values("cpu_s")
        best = f"{100 * mine.total.min():.3g} %" if len(mine) else "no run"
        said = (f"{within.cpu_s.iloc[0]:.3g} CPU s ({within.level.iloc[0]}, {100 * within.total.iloc[0]:.3g} %)"
                if len(within) else f"not reached (best {best})")
        print(f"  implicit 3D to {100 * target:g} %: {said}", flush=True)


def _level(level: dict) -> str:
    return " ".join(f"{k}={v}" for k, v in level.items())


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", help="scenes of the full plan (default: every one with the series)")
    parser.add_argument("--budget", type=float, default=300.0, help="CPU seconds a run may take (default 300)")
    parser.add_argument("--fronts", type=Path, default=FRONTS, help="a report's tables/fronts.csv")
    parser.add_argument("--tiny", action="store_true", help="the thick cylinder's first level, five steps")
    args = parser.parse_args(argv)
    series = {study.case: s for study in full() for s in study.series if s.solver == REF3D_EXPLICIT}
    fronts = pd.read_csv(args.fronts) if args.fronts.exists() else pd.DataFrame(columns=["case", "solver"])
    if args.tiny:
        name = "thick_cylinder"
        measure(name, series[name].levels[:1], dict(series[name].options), math.inf,
                base={"t_end": 5 * get_case(name).dt})
        implicit(name, fronts)
        return
    for name in args.scenes or series:
        measure(name, series[name].levels, dict(series[name].options), args.budget)
        implicit(name, fronts)


if __name__ == "__main__":
    main()
