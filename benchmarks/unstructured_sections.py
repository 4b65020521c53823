"""Does a gmsh section cost accuracy or time? The dome and the rod, mapped and unstructured.

    python benchmarks/unstructured_sections.py [--cases dome rod_impact] [--refine 1 2 4]
                                               [--divisors 1 2 4 8] [--tiny]

Per scene, SMFEM (the moment-scheme element) on the built-in mapped section and on the same
scene with its section from gmsh (``examples/NAME_unstructured.toml``: cases/sections/NAME.msh,
unstructured quadrilaterals), at ``refine`` levels and dt = the case's dt over each divisor:
the total error against the scene's stored truth (smfem/truths/NAME, made on the mapped scene: the
same body, so it judges both) as the quick report measures it (the largest relative max-norm
error over the displacement and velocity probes, the scene's comparison window) and the CPU
time (best of two, one BLAS thread). Then, per section, the least CPU that reaches 1 % and 5 %
along its work-precision front (smfem.studies.metrics), and the ratio unstructured / mapped.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from cases import get_case
from reports.analysis import family_of
from smfem.runs import threads
from smfem.runs.registry import SMFEM, solve
from smfem.studies import metrics
from smfem.studies.stored import directory, read

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def measure(case, repeat: int = 2) -> tuple[float, object]:
    best, result = math.inf, None
    for _ in range(repeat):
        t0 = time.process_time()
        result = solve(SMFEM, case)
        best = min(best, time.process_time() - t0, result.cpu_time_s)
    return best, result


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=["dome", "rod_impact"])
    ap.add_argument("--refine", nargs="+", type=int, default=[1, 2, 4])
    ap.add_argument("--divisors", nargs="+", type=int, default=[1, 2, 4, 8])
    ap.add_argument("--tiny", action="store_true", help="one level, a few steps (the tests run it so)")
    args = ap.parse_args(argv)
    threads.pin()
    for name in args.cases:
        truth = read(directory(name))
        points = {"mapped": [], "unstructured": []}
        for section, source in (("mapped", name), ("unstructured", EXAMPLES / f"{name}_unstructured.toml")):
            for refine in args.refine[:1] if args.tiny else args.refine:
                for divisor in args.divisors[:1] if args.tiny else args.divisors:
                    base = get_case(name)
                    over = {"refine": refine, "dt": base.dt / divisor}
                    if args.tiny:
                        over["t_end"] = 5 * base.dt
                    case = get_case(source, over)
                    cpu, result = measure(case, 1 if args.tiny else 2)
                    err = metrics.headline_error(case, truth, result.t, result.history)
                    points[section].append((cpu, err, f"r{refine} dt/{divisor}"))
                    print(f"{name} {section:12s} r{refine} dt/{divisor}: total error {100 * err:.3g} %, CPU {cpu:.3g} s")
        u = max(truth.uncertainty_of([p.name for p in get_case(name).probes if family_of(p) == "headline"]), 0.0)
        for target in metrics.TARGETS:
            costs = {s: metrics.cost_to(target, *zip(*p), truth_uncertainty=u) for s, p in points.items()}
            ratio = costs["unstructured"].cpu / costs["mapped"].cpu if all(
                c.how == metrics.REACHED for c in costs.values()) else math.nan
            print(f"{name}: CPU to {100 * target:g} %: mapped {costs['mapped'].text()}, unstructured "
                  f"{costs['unstructured'].text()}, ratio {ratio:.3g}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
