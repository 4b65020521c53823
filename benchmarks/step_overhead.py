"""Per-step cost of SMFEM's linear time loop against bare scipy solves with the same factors.

    python benchmarks/step_overhead.py [--set KEY=VALUE ...]

Prints the model size, the CPU time of a whole run and, per step, the framework's time (the
Newmark update, the solve and the probe synthesis) beside the time of ``lu.solve`` alone on the
same factorization. The ratio is the framework overhead (target: under 2).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from cases import get_case, parse_sets
from smfem.model import Model
from smfem.newmark import LinearSystem, march
from smfem.probes import ProbeSet
from smfem.solver import solve
from smfem.stacking import stacked


def best_of(fn, repeat=5):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", nargs="?", default="thick_cylinder")
    ap.add_argument("--set", dest="sets", action="append", default=[])
    ap.add_argument("--tiny", action="store_true", help="a few steps of the smallest settings (the tests run every benchmark so)")
    args = ap.parse_args(argv)
    case = get_case(args.case, {**parse_sets(args.sets), **({"t_end": 1e-4} if args.tiny else {})})

    w0, c0 = time.perf_counter(), time.process_time()
    result = solve(case, with_fields=False)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0

    model = Model(case)
    probes = ProbeSet(model, case.probes)
    K, M, Q, V0, _ = stacked(model)
    system = LinearSystem(K, M, Q, case.dt)
    n = case.n_steps

    def framework():
        for s in march(system, np.zeros_like(Q), V0, case.dt, n):
            probes.evaluate(s.u, s.v)

    rhs = np.random.default_rng(0).normal(size=len(Q))
    bare = lambda: [system.lu.solve(rhs) for _ in range(n)]
    t_fw, t_bare = best_of(framework), best_of(bare)
    print(f"{case.name} {dict(sorted(parse_sets(args.sets).items()))}: {result.n_dof} dof, "
          f"{len(result.info['harmonics_used'])} harmonics computed, {n} steps")
    print(f"  smfem run (solver): wall {wall:.3f} s, cpu {cpu:.3f} s (solver-reported cpu {result.cpu_time_s:.3f} s)")
    print(f"  per step: framework {1e6 * t_fw / n:.1f} us, bare lu.solve {1e6 * t_bare / n:.1f} us, "
          f"ratio {t_fw / t_bare:.2f}")


if __name__ == "__main__":
    from smfem.runs import threads

    threads.pin()  # one BLAS thread, as in smfem's own entry points
    main()
