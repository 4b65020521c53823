"""SMFEM's CPU time on the paper's hardest scenes against the bare triangular solves it needs.

    python benchmarks/speed.py [--tiny]

For each run: CPU time of the solve (best of two), iterations per step, and the time the same
number of bare solves with the run's own factorizations takes (one per iteration; per mode for
the contact layer's base solve): the ratio is what the framework adds on top of the limit.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from cases import get_case
from smfem.contact import ContactSystem
from smfem.iterative import BlockIterative
from smfem.options import SolverOptions
from smfem.solver import solve
from smfem.strategy import build_system

RUNS = (("notched_strip", {"harmonics": 80}), ("notched_strip", {}), ("notched_strip", {"harmonics": 400}),
        ("notched_cylinder", {"harmonics": 40, "refine": 2}), ("thick_cylinder", {"plastic": True}),
        ("rod_impact", {"refine": 4}))


def bare_solve_time(case, iterations: np.ndarray) -> float:
    """CPU time of the solves a run made, with its own factorizations, on random right-hand
    sides: per iteration one solve of the stacked matrix (or one per mode for block Jacobi and the
    paper's block sweep); per step one solve per mode for the contact layer (its state iterations reuse them)."""
    model, system, _ = build_system(case, SolverOptions())
    if isinstance(system, ContactSystem):
        factors, count = system.lus, len(iterations)
    elif isinstance(system, BlockIterative):
        factors, count = system.iteration.factors, int(iterations.sum())
    else:
        factors, count = [system.lu], len(iterations)
    rng = np.random.default_rng(0)
    rhs = [rng.normal(size=s.K.shape[0]) for s in model.systems] if len(factors) > 1 else \
        [rng.normal(size=model.n_dof)]
    t0 = time.process_time()
    for _ in range(count):
        for f, b in zip(factors, rhs):
            f.solve(b)
    return time.process_time() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tiny", action="store_true", help="a few steps of the smallest settings (the tests run every benchmark so)")
    args = ap.parse_args(argv)
    for name, sets in RUNS:
        tiny = {"t_end": 5 * get_case(name).dt, "harmonics": min(sets.get("harmonics", 40), 40)} if args.tiny else {}
        case = get_case(name, {**sets, **tiny})
        cpu = []
        for _ in range(1 if args.tiny else 2):
            t0 = time.process_time()
            r = solve(case, with_fields=False)
            cpu.append(time.process_time() - t0)
        its = np.array(r.iterations)
        bare = bare_solve_time(case, its)
        print(f"{name} {sets}: cpu {min(cpu):.2f} s, {r.n_dof} dof, iterations {its.mean():.2f} / {its.max()}, "
              f"bare solves {bare:.2f} s, ratio {min(cpu) / bare:.1f}  [{r.info['solve'][:60]}]")


if __name__ == "__main__":
    from smfem.runs import threads

    threads.pin()  # one BLAS thread, as in smfem's own entry points
    main()
