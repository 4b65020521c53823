"""How many stress points along x3 the plastic scenes need (``SolverOptions.x3_oversampling``).

    python benchmarks/x3_points.py [--factors 1 1.5 2 3] [--tiny]

The plastic strains live at Gauss-Legendre points along x3; ``x3_oversampling = 1`` is the
fewest that integrate the kept modes' products exactly (smfem/sampling.py), without the floor
of ``x3_min_points``; then the default (that floor, 256 points). For the plastic thick
cylinder, notched cylinder and notched strip: the points, CPU time and how far each probe
moves from a run with 6 times the fewest (tol 1e-10, so that the iterations do not blur it),
relative to the probe's largest value.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from cases import get_case
from smfem.options import SolverOptions
from smfem.solver import solve

SCENES = (("thick_cylinder", {"plastic": True}), ("notched_cylinder", {}), ("notched_strip", {"t_end": 1.6e-4}))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--factors", type=float, nargs="+", default=[1.0, 1.5, 2.0, 3.0])
    ap.add_argument("--tiny", action="store_true", help="a few steps of the smallest settings (the tests run every benchmark so)")
    args = ap.parse_args(argv)
    factors, finest = ([1.0], 2.0) if args.tiny else (args.factors, 6.0)
    for name, sets in SCENES:
        sets = {**sets, "tol": 1e-10, **({"t_end": 5 * get_case(name).dt} if args.tiny else {})}
        case = get_case(name, sets)
        ref = solve(case, SolverOptions(x3_oversampling=finest, x3_min_points=0), with_fields=False).history
        for label, options in [(f"x3_oversampling {f:g}", SolverOptions(x3_oversampling=f, x3_min_points=0))
                               for f in factors] + [("default", SolverOptions())]:
            t0 = time.process_time()
            r = solve(case, options, with_fields=False)
            cpu = time.process_time() - t0
            off = {p: np.abs(r.history[p] - ref[p]).max() / max(np.abs(ref[p]).max(), 1e-300) for p in ref}
            print(f"{name} {label}: {r.info['n_x3_points']} points, cpu {cpu:.2f} s; off the "
                  f"{finest:g}x run: " + ", ".join(f"{p} {v:.1e}" for p, v in off.items()))


if __name__ == "__main__":
    from runs import threads

    threads.pin()  # one BLAS thread, as in smfem's own entry points
    main()
