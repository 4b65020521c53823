"""How many stress points along x3 SMFEM's plastic scenes need, per scene and harmonic count.

    python benchmarks/x3_points.py [--write] [--scenes NAME ...] [--tiny]

For each plastic scene and each harmonic count its studies run: SMFEM from the fewest
points (:func:`smfem.inhomogeneity.x3_rule`) that integrate the kept modes exactly
(``x3_oversampling = 1``), the count doubled until the plastic-zone area (peps >= 0.1 %, at each of the scene's zone times)
moves by at most 1 % of the zone's largest area when it doubles once more
(:data:`cases.x3_points.AREA_TOLERANCE`; at most 16 times the exact count). Prints every
doubling (points, CPU, areas, change) and the chosen count; ``--write`` stores the choices in
``cases/x3_points.csv``, which SMFEM's plastic runs read (:mod:`cases.x3_points`).
"""

from __future__ import annotations

import argparse
import time

import pandas as pd

from cases import get_case
from cases.x3_points import AREA_TOLERANCE, TABLE
from smfem.runs.zones import plastic_area
from smfem.options import SolverOptions
from smfem.solver import solve

#: scene -> (its plastic settings, the harmonic counts its studies and checks run)
SCENES = {"thick_cylinder": ({"plastic": True}, (20, 40, 80)),
          "notched_cylinder": ({}, (20, 40, 80)),
          "notched_strip": ({}, (40, 80, 120, 160, 240, 400))}
#: the largest multiple of the exact count tried
MAX_FACTOR = 16


def zone_areas(case, factor: float) -> tuple[list[float], int, float]:
    """Plastic-zone areas at the scene's zone times, the points along x3 and the CPU time."""
    t0 = time.process_time()
    r = solve(case, SolverOptions(x3_oversampling=factor), with_fields=False)
    return [plastic_area(s) for s in r.snapshots], r.info["n_x3_points"], time.process_time() - t0


def change(a, b) -> float:
    """Largest change of the areas ``a`` against ``b``, relative to the largest of ``b``."""
    scale = max(b)
    return max(abs(x - y) for x, y in zip(a, b)) / scale if scale > 0 else float(any(a))


def calibrate(name: str, sets: dict, harmonics: int) -> dict:
    """The smallest power-of-2 multiple of the exact count whose areas one more doubling moves
    by at most the tolerance (or :data:`MAX_FACTOR`)."""
    case = get_case(name, {**sets, "harmonics": harmonics})
    factor, (areas, points, cpu) = 1, zone_areas(case, 1)
    exact = points
    while True:
        areas2, points2, cpu2 = zone_areas(case, 2 * factor)
        moved = change(areas, areas2)
        print(f"{name} H{harmonics}: {points} points ({factor}x) {cpu:.2f} s CPU, areas "
              f"{', '.join(f'{a:.4g}' for a in areas)}; doubled ({points2}): moved {100 * moved:.2f} %", flush=True)
        if moved <= AREA_TOLERANCE or 2 * factor > MAX_FACTOR:
            return {"scene": name, "harmonics": harmonics, "exact_points": exact, "points": points,
                    "factor": factor, "area_change_pct": 100 * moved}
        factor, areas, points, cpu = 2 * factor, areas2, points2, cpu2


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="+", default=list(SCENES), choices=list(SCENES))
    ap.add_argument("--write", action="store_true", help=f"store the choices in {TABLE}")
    ap.add_argument("--tiny", action="store_true", help="a few steps of the smallest settings (the tests run every benchmark so)")
    args = ap.parse_args(argv)
    if args.tiny:
        case = get_case("thick_cylinder", {"plastic": True, "t_end": 5 * get_case("thick_cylinder").dt})
        for factor in (1, 2):
            _, points, cpu = zone_areas(case, factor)
            print(f"tiny: {factor}x the exact count: {points} points, {cpu:.2f} s CPU")
        return
    rows = [calibrate(name, SCENES[name][0], h) for name in args.scenes for h in SCENES[name][1]]
    table = pd.DataFrame(rows)
    print(table.to_string(index=False))
    if args.write:
        if set(args.scenes) != set(SCENES) and TABLE.exists():  # keep the other scenes' rows
            old = pd.read_csv(TABLE)
            table = pd.concat([old[~old.scene.isin(args.scenes)], table], ignore_index=True)
        table.to_csv(TABLE, index=False, float_format="%.4g")
        print(f"-> {TABLE}")


if __name__ == "__main__":
    from smfem.runs import threads

    threads.pin()  # one BLAS thread, as in smfem's own entry points
    main()
