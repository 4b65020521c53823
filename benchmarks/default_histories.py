"""Every scene's default histories, both solvers: record them, or compare with a recording.

    python benchmarks/default_histories.py [--record DIR] [--tiny]   # default DIR: out/default-histories
    python benchmarks/default_histories.py --compare DIR [--tiny]

A refactor that must leave the results alone (issue "one table per extension point") records
first and compares after: per scene, solver and probe the largest difference over the history
relative to the probe's largest value. ``--compare`` exits 1 when one exceeds ``--rtol``
(default 1e-9: round-off, not a change of method).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from cases import CASES, get_case
from smfem.runs import threads
from smfem.runs.registry import REFERENCE, SMFEM, solve

SOLVERS = (SMFEM, REFERENCE)
#: the reference's settings where its default is past a direct solver: the flywheel's 3D model
#: (its 808-element section swept into 51,712 27-node hexahedra, 1.3 million unknowns) is its
#: axisymmetric 2D form here, the same mesh-section code path (the rings in contact run in plane
#: strain by default: 3 CPU s)
REFERENCE_SETTINGS = {"flywheel": {"patch_deg": 180.0, "dim": 2}}


def histories(name: str, solver: str, tiny: bool) -> dict[str, np.ndarray]:
    base = REFERENCE_SETTINGS.get(name, {}) if solver == REFERENCE else {}
    case = get_case(name, base)
    if tiny:
        case = get_case(name, {**base, "t_end": 5 * case.dt})
    result = solve(solver, case)
    return {"t": result.t, **result.history}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    what = ap.add_mutually_exclusive_group()
    what.add_argument("--record", type=Path, metavar="DIR")
    what.add_argument("--compare", type=Path, metavar="DIR")
    ap.add_argument("--rtol", type=float, default=1e-9)
    ap.add_argument("--tiny", action="store_true", help="five steps of each scene (the tests run every benchmark so)")
    args = ap.parse_args(argv)
    if args.compare is None and args.record is None:
        args.record = Path("out/default-histories")
    threads.pin()
    worst = 0.0
    for name in CASES:
        for solver in SOLVERS:
            now = histories(name, solver, args.tiny)
            file = (args.record or args.compare) / f"{name}-{solver}.npz"
            if args.record:
                file.parent.mkdir(parents=True, exist_ok=True)
                np.savez(file, **now)
                print(f"{name} {solver}: {len(now['t'])} times recorded")
                continue
            before = np.load(file)
            diffs = {p: float(np.abs(now[p] - before[p]).max() / max(np.abs(before[p]).max(), 1e-300))
                     for p in before.files if p != "t"}
            probe = max(diffs, key=diffs.get)
            worst = max(worst, diffs[probe])
            print(f"{name} {solver}: largest relative difference {diffs[probe]:.2e} ({probe})")
    if args.compare:
        print(f"worst {worst:.2e} (rtol {args.rtol:g})")
    return 0 if worst <= args.rtol else 1


if __name__ == "__main__":
    sys.exit(main())
