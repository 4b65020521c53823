"""How honest is a run's error estimate? Effectivity = estimate / actual error, per probe.

For each scene and solver (SMFEM, the 2D reference) at the scene's defaults and two other
settings (refine 2; half the step), the run's estimate (runs.estimate) against its actual
error from the stored truth (truths/CASE), on the displacement and velocity probes whose
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
from reports.effectivity import settings  # noqa: E402
from reports.metrics import TRUTH_MARGIN  # noqa: E402
from reports.stored import directory, read  # noqa: E402
from runs import threads  # noqa: E402
from runs.errors import history_errors  # noqa: E402
from runs.estimate import PARTS, estimate  # noqa: E402
from runs.registry import REF2D, SMFEM, solve  # noqa: E402


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
    fields = {p.name: p.field for p in case.probes}
    out = []
    for probe, parts in est.get("probes", {}).items():
        if fields.get(probe) not in ("u", "v") or probe not in truth.values or not truth.converged(probe):
            continue
        actual = history_errors(result.t, result.history[probe], truth.t, truth.values[probe],
                                truth.window)[0]
        u = truth.uncertainty_of([probe])
        out.append({"case": name, "solver": solver, "setting": label, "probe": probe, "actual": actual,
                    "estimate": parts["total"], "effectivity": parts["total"] / actual if actual > 0 else float("nan"),
                    **{f"est_{k}": parts[k] for k in PARTS if k in parts},
                    **{f"order_{k}": v for k, v in parts["orders"].items()},
                    "truth_fine_enough": actual > TRUTH_MARGIN * u, "run_cpu_s": result.cpu_time_s,
                    "companions_cpu_s": est["companions_cpu_total_s"], "wall_s": wall})
    return out


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
    judged = table[table.truth_fine_enough]
    print(f"\neffectivity over {len(judged)} probes with a fine-enough truth: "
          f"{judged.effectivity.min():.2f} ... {judged.effectivity.max():.2f}; "
          f"outside [0.8, 3]: {int(((judged.effectivity < 0.8) | (judged.effectivity > 3)).sum())}")
    print(f"companions' CPU / run CPU: {(table.companions_cpu_s / table.run_cpu_s).groupby(table.case).max().round(2).to_dict()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
