"""Rod impact on a tilted wall (contact that is not axisymmetric): SMFEM against the 3D reference.

    python benchmarks/tilted_wall.py            # reference 3D at refine 1 (about 30-45 s per run)
    python benchmarks/tilted_wall.py --fine     # also the reference at refine 2 (about 8 min)

For friction 0 and 0.3, runs SMFEM at (refine, harmonics) = (1, 6), (1, 12), (2, 12) and the
reference FEM in 3D, and prints each SMFEM run's relative max-norm error per probe against each
reference run (in brackets: through the 2R/c window), its size, CPU time, state iterations
per step and the energy lost over the run (friction dissipates; without it the layer
conserves energy).
"""

from __future__ import annotations

import argparse
import time

from cases import get_case
from reference_fem import solve as reference
from smfem.studies.metrics import history_errors
from smfem.solver import solve

SLOPE = 0.01
SMFEM_RUNS = ((1, 6), (1, 12), (2, 12))


def timed(solver, case):
    t0 = time.process_time()
    r = solver(case)
    return r, time.process_time() - t0


def lost(r) -> float:
    return 1 - r.info["energy_after"] / r.info["energy_before"]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fine", action="store_true", help="also the reference 3D at refine 2")
    parser.add_argument("--tiny", action="store_true", help="a few steps of the smallest settings (the tests run every benchmark so)")
    args = parser.parse_args(argv)
    for friction in (0.3,) if args.tiny else (0.0, 0.3):
        base = {"wall_slope": SLOPE, "friction": friction, **({"t_end": 1e-5} if args.tiny else {})}
        refs = {}
        for refine in (1, 2) if args.fine else (1,):
            r, cpu = timed(reference, get_case("rod_impact", dict(base, dim=3, refine=refine)))
            refs[refine] = r
            print(f"friction {friction}: reference 3D refine {refine}: {r.n_dof} dof, cpu {cpu:.1f} s, "
                  f"energy lost {lost(r):.2%}")
        for refine, harmonics in SMFEM_RUNS[:1] if args.tiny else SMFEM_RUNS:
            case = get_case("rod_impact", dict(base, refine=refine, harmonics=harmonics))
            s, cpu = timed(solve, case)
            window = case.references["comparison_window_s"]
            print(f"  SMFEM refine {refine}, {harmonics} harmonics: {s.n_dof} dof, cpu {cpu:.1f} s, iterations "
                  f"{s.info['iterations_mean']:.2f}/{s.info['iterations_max']}, energy lost {lost(s):.2%}")
            for ref_refine, r in refs.items():
                cells = []
                for probe, a in s.history.items():
                    raw = history_errors(s.t, a, r.t, r.history[probe])[0]
                    seen = history_errors(s.t, a, r.t, r.history[probe], window=window)[0]
                    cells.append(f"{probe} {raw:.1%} ({seen:.1%})")
                print(f"    against reference refine {ref_refine}: " + ", ".join(cells))


if __name__ == "__main__":
    from smfem.runs import threads

    threads.pin()  # one BLAS thread, as in smfem's own entry points
    main()
