"""A load turning round a ring: SMFEM against the reference FEM in 2D and 3D, same dt.

    python benchmarks/turning_patches.py [--quick] [--tiny]

The scene ``examples/turning_patches.toml``: the thick cylinder's two 90 deg patches turning at
500 rad/s. Each run at the scene's dt (so the differences are spatial: mesh and harmonics,
not time): SMFEM at refine 1, 2, 4 with 20, 40, 80 harmonics; the reference FEM's plane model
(the plane strain ring's own plane holds the turning load) at refine 1, 2, 4 and its 3D model
at refine 1, 2. Per pair, the relative max-norm difference of each probe over the window, and
each run's CPU time and the harmonics SMFEM used (both families).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from cases import get_case
from smfem.runs.errors import probe_error
from smfem.runs.threads import pin
from smfem.runs.registry import REFERENCE, SMFEM, solve

SCENE = Path(__file__).resolve().parents[1] / "examples" / "turning_patches.toml"


def difference(a, b, probes) -> dict[str, float]:
    return {p: probe_error(p, a.t, a.history[p], b.t, b.history[p])[1] for p in probes}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="refine 1 and 2 only")
    parser.add_argument("--tiny", action="store_true", help="refine 1 and 2 (3D: 1) over five steps (the tests run every benchmark so)")
    args = parser.parse_args(argv)
    pin()
    levels = (1, 2) if args.quick or args.tiny else (1, 2, 4)
    window = {"t_end": 5 * get_case(SCENE).dt} if args.tiny else {}
    runs = {}
    for r in levels:
        runs["SMFEM", r] = solve(SMFEM, get_case(SCENE, {"refine": r, "harmonics": 20 * r, **window}))
        runs["2D", r] = solve(REFERENCE, get_case(SCENE, {"refine": r, "dim": 2, **window}))
    levels_3d = (1,) if args.tiny else levels[:2]  # the 3D r2 factorization is the tiny run's cost
    for r in levels_3d:
        runs["3D", r] = solve(REFERENCE, get_case(SCENE, {"refine": r, "dim": 3, **window}))
    probes = get_case(SCENE).probe_names
    for key, run in runs.items():
        used = run.info.get("harmonics_used", "")
        print(f"{key[0]:>5} r{key[1]}: CPU {run.cpu_time_s:7.2f} s, {run.n_dof} unknowns" + (f", harmonics {used}" if used else ""))
    finest = max(levels)
    finest_3d = max(levels_3d)
    pairs = [(("SMFEM", finest), ("3D", finest_3d)), (("SMFEM", finest), ("2D", finest)), (("2D", finest), ("3D", finest_3d)),
             (("SMFEM", 1), ("3D", 1))]
    for a, b in pairs:
        d = difference(runs[a], runs[b], probes)
        print(f"{a[0]} r{a[1]} - {b[0]} r{b[1]}: " + ", ".join(f"{p} {100 * v:.3f} %" for p, v in d.items()))


if __name__ == "__main__":
    main()
