"""Cost of an elastic SMFEM run against the number of Fourier terms (thick cylinder).

    python benchmarks/harmonics_cost.py [--counts 25 50 100 200 400 800] [--set KEY=VALUE ...]

Two loads: the case's two opposite patches (harmonics l = 0 and l = 2 mod 4 carry load, so a
quarter of the terms are computed) and one patch over 0..50 deg, which loads every harmonic of
both Fourier families (twice as many modes as terms). For each count: modes computed, dof, the
best of three wall times of a whole run (model, factorization, time stepping, probes) and the
time per mode. The fit ``time = a + b * modes`` and the log-log slope between the two largest
counts tell whether the cost grows linearly (slope 1).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import time

import numpy as np

from cases import get_case, parse_sets
from cases.geometry import Pressure
from smfem.solver import solve


def one_patch(case):
    return dataclasses.replace(case, loads=(Pressure(case.loads[0].q, "outer", ((0.0, math.radians(50.0)),)),))


def best_wall(case, repeat=3):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = solve(case, with_fields=False)
        times.append(time.perf_counter() - t0)
    return min(times), result


def measure(counts, sets, load):
    rows = []
    for n in counts:
        case = get_case("thick_cylinder", dict(sets, harmonics=n))
        wall, result = best_wall(one_patch(case) if load == "one patch" else case)
        modes = len(result.info["harmonics_used"])
        assert all(np.isfinite(h).all() for h in result.history.values())
        rows.append({"load": load, "harmonics": n, "modes": modes, "n_dof": result.n_dof, "steps": case.n_steps,
                     "wall_s": wall, "ms_per_mode": 1e3 * wall / modes})
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--counts", type=int, nargs="+", default=[25, 50, 100, 200, 400, 800])
    ap.add_argument("--set", dest="sets", action="append", default=["refine=2", "dt=1e-5"])
    ap.add_argument("--tiny", action="store_true", help="a few steps of the smallest settings (the tests run every benchmark so)")
    args = ap.parse_args(argv)
    sets = parse_sets(args.sets)
    if args.tiny:
        args.counts, sets = [4, 8], dict(sets, refine=1, t_end=1e-4)
    print(f"thick_cylinder {sets}")
    for load in ("two patches", "one patch"):
        rows = measure(args.counts, sets, load)
        print(f"{load}:")
        for r in rows:
            print(f"  {r['harmonics']:5d} harmonics  {r['modes']:5d} modes  {r['n_dof']:7d} dof  {r['steps']} steps  "
                  f"wall {r['wall_s']:.3f} s  {r['ms_per_mode']:.2f} ms per mode")
        modes = np.array([r["modes"] for r in rows], float)
        wall = np.array([r["wall_s"] for r in rows])
        b, a = np.polyfit(modes, wall, 1)
        fit = a + b * modes
        r2 = 1 - ((wall - fit) ** 2).sum() / ((wall - wall.mean()) ** 2).sum()
        slope = math.log(wall[-1] / wall[-2]) / math.log(modes[-1] / modes[-2])
        print(f"  fit: wall = {a:.3f} s + {1e3 * b:.2f} ms x modes (R^2 = {r2:.4f}); "
              f"log-log slope between the two largest counts {slope:.2f}")


if __name__ == "__main__":
    from smfem.runs import threads

    threads.pin()  # one BLAS thread, as in smfem's own entry points
    main()
