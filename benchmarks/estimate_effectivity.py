"""How honest is a run's error estimate? Effectivity = estimate / actual error, per probe.

For each scene and solver (SMFEM, the 2D reference) at the scene's defaults and two other
settings (refine 2; half the step), the run's estimate (smfem.runs.estimate) against its actual
error from the stored truth (smfem/truths/CASE), on the displacement and velocity probes whose
truth is fine enough (actual error above three times the truth's uncertainty).

    python benchmarks/estimate_effectivity.py [--cases dome thick_cylinder ...] [--out FILE.csv]

Writes a CSV (one row per scene, solver, setting, probe) and prints the table and the range.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from cases import CASES, get_case  # noqa: E402
from smfem.studies.effectivity import judged, settings, summary  # noqa: E402
from smfem.studies.stored import directory, read  # noqa: E402
from smfem.runs import threads  # noqa: E402
from smfem.runs.estimate import estimate  # noqa: E402
from smfem.runs.registry import REF2D, SMFEM, solve  # noqa: E402


def settings_of(name: str, tiny: bool = False) -> dict[str, dict]:
    if tiny:  # the test suite's size: a tenth of the window, the defaults only
        return {"defaults (t_end / 10)": {"t_end": get_case(name).t_end / 10}}
    return settings(name)  # the report's


def rows_for(name: str, solver: str, label: str, overrides: dict, truth) -> list[dict]:
    case = get_case(name, overrides)
    wall = time.perf_counter()
    result = solve(solver, case)
    est = estimate(case, solver, result)
    wall = time.perf_counter() - wall
    return [{"case": name, "solver": solver, "setting": label, **row, "wall_s": wall}
            for row in judged(case, truth, result.t, result.history, est)]


def main(argv=None) -> int:
    threads.pin()
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="*", default=list(CASES))
    parser.add_argument("--solvers", nargs="*", default=[SMFEM, REF2D])
    parser.add_argument("--out", default="out/benchmarks/estimate_effectivity.csv")
    parser.add_argument("--tiny", action="store_true", help="thick cylinder, SMFEM, a tenth of the window")
    args = parser.parse_args(argv)
    if args.tiny:
        args.cases, args.solvers = ["thick_cylinder"], [SMFEM]
    rows = []
    for name in args.cases:
        truth = read(directory(name))
        for solver in args.solvers:
            for label, overrides in settings_of(name, args.tiny).items():
                rows += rows_for(name, solver, label, overrides, truth)
                print(pd.DataFrame(rows[-1:]).to_string(index=False, header=len(rows) == 1), flush=True)
    table = pd.DataFrame(rows)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(args.out, index=False, float_format="%.4g")
    print(f"\n{summary(table)}")
    print(f"companions' CPU / run CPU: {(table.companions_cpu_s / table.run_cpu_s).groupby(table.case).max().round(2).to_dict()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
