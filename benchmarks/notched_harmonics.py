"""Convergence and cost of SMFEM in the number of Fourier terms on the notched scenes.

    python benchmarks/notched_harmonics.py [--case notched_strip] [--counts 20 40 80 160 240 400]
                                          [--truth DIR] [--set KEY=VALUE ...] [--tiny]

For each count: CPU time of the run (one BLAS thread gives the figures in benchmarks/README.md),
iterations per step, and each probe's error: against the run with the most terms
(convergence in the terms alone, at the case's mesh and time step) and, with ``--truth`` (a
``smfem truth`` output directory), against the truth (the total error: terms, mesh and time
together). Displacements: relative max-norm; plastic strains: the relative difference of the
peaks. Then the log-log slope of CPU time against the count over the counts from 40 up: the
exponent of the cost.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np
import pandas as pd

from cases import get_case, parse_sets
from smfem.runs.errors import probe_error
from smfem.solver import solve


def run(name: str, sets: dict, harmonics: int):
    case = get_case(name, {**sets, "harmonics": harmonics})
    t0 = time.process_time()
    result = solve(case, with_fields=False)
    return result, time.process_time() - t0


def errors(result, t_ref: np.ndarray, ref: dict) -> dict[str, float]:
    return {p: probe_error(p, result.t, result.history[p], t_ref, np.asarray(ref[p]))[1] for p in result.history if p in ref}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="notched_strip", choices=("notched_strip", "notched_cylinder"))
    ap.add_argument("--counts", type=int, nargs="+", default=None)
    ap.add_argument("--truth", type=Path, help="a `smfem truth` output directory of the same case")
    ap.add_argument("--set", action="append", default=[], help="KEY=VALUE overrides of the case")
    ap.add_argument("--tiny", action="store_true", help="a few steps of the smallest settings (the tests run every benchmark so)")
    args = ap.parse_args(argv)
    sets = parse_sets(args.set)
    default = {"notched_strip": [20, 40, 80, 160, 240, 400], "notched_cylinder": [10, 20, 40, 80]}[args.case]
    counts = sorted(args.counts or ([8, 12] if args.tiny else default))
    if args.tiny:
        sets["t_end"] = 5 * get_case(args.case).dt
    truth = None
    if args.truth:
        truth = pd.read_csv(args.truth / "history.csv")
        uncertainty = json.loads((args.truth / "summary.json").read_text()).get("uncertainty", {})
        print(f"truth: {args.truth} (uncertainty {uncertainty})")
    runs = {H: run(args.case, sets, H) for H in counts}
    finest = runs[counts[-1]][0]
    rows = []
    for H, (r, cpu) in runs.items():
        row = {"harmonics": H, "cpu_s": round(cpu, 2), "iterations": round(float(np.mean(r.iterations)), 2),
               "converged": r.converged}
        row.update({f"{p} vs H{counts[-1]}": f"{e:.2e}" for p, e in errors(r, finest.t, finest.history).items()})
        if truth is not None:
            row.update({f"{p} vs truth": f"{e:+.2e}" for p, e in errors(r, truth["t"].to_numpy(), truth).items()})
        rows.append(row)
    print(pd.DataFrame(rows).to_string(index=False))
    fit = [(H, c) for H, (_, c) in runs.items() if H >= 40]
    if len(fit) >= 2:
        slope = np.polyfit(np.log([h for h, _ in fit]), np.log([c for _, c in fit]), 1)[0]
        print(f"cost ~ harmonics^{slope:.2f} (log-log fit over {[h for h, _ in fit]})")
    else:
        print(f"cost exponent: needs two counts from 40 up (have {counts}); "
              + ("" if len(counts) < 2 else f"slope {math.log(runs[counts[-1]][1] / runs[counts[0]][1]) / math.log(counts[-1] / counts[0]):.2f}"))


if __name__ == "__main__":
    from smfem.runs import threads

    threads.pin()  # one BLAS thread, as in smfem's own entry points
    main()
