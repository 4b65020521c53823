"""The reference FEM's Newton tangents: factorized (SuperLU) against CG on the elastic factors.

    python benchmarks/reference_linear_solver.py [--runs notched_cylinder:3:1 ...] [--tiny]

Each run (scene, dim, refine; the case's dt and window) once with ``linear_solver=superlu`` and
once with ``pcg``: CPU time (one thread), peak memory of the process so far, factorizations,
CG iterations, Newton iterations, and the largest history difference relative to each probe's
largest value. Elastic scenes have no tangent: both settings are the same numerics there.
"""

from __future__ import annotations

import argparse
import resource

from smfem.runs.threads import pin

pin()

import numpy as np  # noqa: E402

from cases import get_case  # noqa: E402
from smfem.runs.registry import solve  # noqa: E402

RUNS = ("notched_strip:3:1", "notched_cylinder:3:1", "notched_cylinder:3:2", "notched_strip:3:2")


def measure(name: str, dim: int, refine: int, sets: dict | None = None) -> list[dict]:
    case = get_case(name, {"dim": dim, "refine": refine, **(sets or {})})
    runs = {how: solve("reference", case, options={"linear_solver": how}) for how in ("superlu", "pcg")}
    diff = max(float(np.abs(runs["pcg"].history[p] - h).max() / (np.abs(h).max() or 1.0))
               for p, h in runs["superlu"].history.items())
    return [{"scene": f"{name} {dim}D r{refine}", "solver": how, "n_dof": r.n_dof, "cpu_s": r.cpu_time_s,
             "factorizations": r.info["factorizations"], "cg_iterations": r.info.get("cg_iterations", 0),
             "newton_mean": float(np.mean(r.iterations)), "history_difference": diff,
             "peak_rss_GB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6}
            for how, r in runs.items()]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", nargs="*", default=RUNS, help="scene:dim:refine")
    parser.add_argument("--tiny", action="store_true", help="the strip in 2D up to its first yielding steps")
    args = parser.parse_args(argv)
    # the strip's first point yields at its 14th step (3.2e-6 s each)
    runs, sets = (["notched_strip:2:1"], {"t_end": 6.4e-5}) if args.tiny else (args.runs, None)
    print(f"{'run':26} {'solver':8} {'dofs':>7} {'CPU s':>8} {'factors':>7} {'CG its':>7} {'Newton':>6} "
          f"{'diff':>8} {'peak GB':>7}")
    for item in runs:
        name, dim, refine = item.split(":")
        for row in measure(name, int(dim), int(refine), sets):
            print(f"{row['scene']:26} {row['solver']:8} {row['n_dof']:7d} {row['cpu_s']:8.2f} {row['factorizations']:7d} "
                  f"{row['cg_iterations']:7d} {row['newton_mean']:6.2f} {row['history_difference']:8.1e} "
                  f"{row['peak_rss_GB']:7.2f}", flush=True)


if __name__ == "__main__":
    main()
