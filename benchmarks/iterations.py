"""Iterations per step, relaxation and cost breakdown of the nonlinear SMFEM solver.

    python benchmarks/iterations.py

Prints, for the plastic thick cylinder, notched cylinder and notched strip, the mean and
maximum iterations per step at tol 1e-5, 1e-8 and 1e-10, with Anderson acceleration and without
(the paper's plain iteration), how far the probes are from a run at tol 1e-12 (the largest
difference over the probes, relative to each probe's largest value) and the time spent per
iteration in synthesis (trial stresses of the amplitudes), the stress update (Wilkins), the
projection of the additional loads (14) and the solves; then a small study of the block-SOR relaxation omega, and direct against iterative
timings of an elastic inhomogeneous run (the coupled
factorization against conjugate gradients with the coupling applied matrix-free).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from cases import get_case
from smfem.options import SolverOptions
from smfem.solver import solve


def relative_error(a, b, probe: str) -> float:
    """Largest difference of a probe's histories, relative to the largest value of ``b``'s."""
    n = min(len(a.history[probe]), len(b.history[probe]))
    scale = np.abs(b.history[probe]).max()
    return float(np.abs(a.history[probe][:n] - b.history[probe][:n]).max() / scale) if scale > 0 else 0.0


def run(name, options=None, **sets):
    t0 = time.process_time()
    r = solve(get_case(name, sets), options, with_fields=False)
    return r, time.process_time() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tiny", action="store_true", help="a few steps of the smallest settings (the tests run every benchmark so)")
    tiny = ap.parse_args(argv).tiny
    window = lambda name: {"t_end": 5 * get_case(name).dt} if tiny else {}
    for name in ("thick_cylinder", "notched_cylinder", "notched_strip"):
        converged, _ = run(name, plastic=True, tol=1e-12, **window(name))
        for tol in (1e-5, 1e-8, 1e-10):
            for memory in (0, 5):
                r, cpu = run(name, SolverOptions(anderson=memory), plastic=True, tol=tol, **window(name))
                n_it = sum(r.iterations)
                per = {k: 1e3 * v / n_it for k, v in r.info["time_breakdown_s"].items()}
                off = max(relative_error(r, converged, p) for p in r.history)
                print(f"{name} tol={tol:g} anderson={memory}: converged={r.converged} iterations mean "
                      f"{r.info['iterations_mean']:.2f} max {r.info['iterations_max']}, cpu {cpu:.2f} s, probes off "
                      f"the tol 1e-12 run by {off:.1e}; per iteration (ms): "
                      + ", ".join(f"{k} {v:.3f}" for k, v in per.items()))
    for omega in (1.0,) if tiny else (0.8, 1.0, 1.2, 1.5):
        r, cpu = run("thick_cylinder", SolverOptions(iteration_matrix="sor", relaxation=omega), plastic=True, **window("thick_cylinder"))
        print(f"omega {omega}: thick_cylinder plastic iterations mean {r.info['iterations_mean']:.2f} "
              f"max {r.info['iterations_max']}, cpu {cpu:.2f} s")
    for matrix in ("coupled", "matrix-free"):
        t0 = time.process_time()
        r = solve(get_case("notched_cylinder", {"plastic": False, "t_end": 2e-4 if tiny else 1e-3}),
                  SolverOptions(iteration_matrix=matrix), with_fields=False)
        print(f"notched_cylinder elastic, 10 steps, {matrix}: cpu {time.process_time() - t0:.3f} s, "
              f"iterations mean {np.mean(r.iterations):.1f}, converged {r.converged}  [{r.info['solve'][:50]}]")


if __name__ == "__main__":
    from smfem.runs import threads

    threads.pin()  # one BLAS thread, as in smfem's own entry points
    main()
