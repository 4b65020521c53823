"""How far the reference FEM's own probes move under mesh refinement on the notched scenes.

    python benchmarks/notched_convergence.py [--levels 1 2 3 4] [--cache out/benchmarks/runs]

Runs the 2D reference on ``notched_cylinder`` and ``notched_strip`` (plastic, the case's time
step) at each refine level, through the report's run cache, and prints per probe the relative
max-norm difference between consecutive levels (over the window all levels cover), the peak
of each level and the observed order. A probe whose differences do not shrink has no
converged truth: the cases name such probes under ``references['singular_probes']``, and the
truth leaves them out. Refine 4 takes about 10 (strip) and 15 (cylinder) CPU minutes.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from cases import get_case
from smfem.studies.cache import RunCache
from smfem.studies.jobs import Job
from smfem.studies.plan import REF2D
from smfem.studies.study import run_cached
from smfem.studies.truth import order_of

CASES = ("notched_cylinder", "notched_strip")


def table(runs: dict) -> list[dict]:
    """Per case and probe: differences between consecutive levels, peaks, observed order."""
    rows = []
    for name in CASES:
        levels = sorted(r for (c, r) in runs if c == name)
        done = {r: runs[name, r] for r in levels if runs[name, r].usable}
        end = min(run.history["t"].iloc[-1] for run in done.values())
        grid = next(iter(done.values())).history["t"].to_numpy()
        grid = grid[grid <= end * (1 + 1e-12)]
        for probe in get_case(name).probe_names:  # the same probes whatever the window
            q = {r: np.interp(grid, run.history["t"], run.history[probe]) for r, run in done.items()}
            rs = sorted(q)
            top = np.abs(q[rs[-1]]).max()
            diffs = [float(np.abs(q[b] - q[a]).max() / top) if top else math.nan for a, b in zip(rs, rs[1:])]
            orders = [order_of([1 / r for r in rs[i:i + 3]], diffs[i], diffs[i + 1]) for i in range(len(diffs) - 1)]
            rows.append({"case": name, "probe": probe, "levels": rs, "end_s": float(end),
                         "differences": diffs, "orders": orders,
                         "peaks": [float(q[r][np.argmax(np.abs(q[r]))]) for r in rs]})
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", type=int, nargs="+", default=[1, 2, 3, 4])
    parser.add_argument("--cache", default="out/benchmarks/runs")
    parser.add_argument("--tiny", action="store_true", help="a few steps of the smallest settings (the tests run every benchmark so)")
    args = parser.parse_args(argv)
    base = lambda name: {"t_end": 3 * get_case(name).dt} if args.tiny else {}
    if args.tiny:
        args.levels = [1, 2, 3]
    jobs = {(name, r): Job.make(name, REF2D, {**base(name), "refine": r}) for name in CASES for r in args.levels}
    done, executed, _ = run_cached(list(jobs.values()), RunCache(Path(args.cache)), workers=2)
    runs = {key: done[job] for key, job in jobs.items()}
    for key, run in runs.items():
        if run.status != "ok":
            print(f"{key[0]} refine {key[1]}: {run.status}: {run.message}")
    for row in table(runs):
        fmt = lambda xs, f: ", ".join(f.format(x) if math.isfinite(x) else "nan" for x in xs)
        print(f"{row['case']:<17} {row['probe']:<11} refine {row['levels']} (t <= {row['end_s']:.3g} s): "
              f"differences {fmt([100 * d for d in row['differences']], '{:.3g} %')}; "
              f"orders {fmt(row['orders'], '{:.2f}')}; peaks {fmt(row['peaks'], '{:.4g}')}")


if __name__ == "__main__":
    from smfem.runs import threads

    threads.pin()  # one BLAS thread, as in smfem's own entry points
    main()
