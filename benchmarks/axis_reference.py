"""The 3D reference on sections that reach the axis (reference_fem/ties.py), and SMFEM against it.

    python benchmarks/axis_reference.py [--manufactured] [--puck] [--fine] [--halve] [--tiny]

``--manufactured``: the motion through the axis (cases/verification_axis.py, five steps of t^2,
exact in time): the 3D reference's L2 error with the section split k x k and 4 k elements round,
k = 1, 2, 3, and SMFEM's (moment4 and quad9, k = 1 ... 8), with the observed orders.

``--puck``: the example examples/puck_strike.toml (a gmsh disc through the axis, struck off it),
all at the scene's step (``--halve``: half of it): SMFEM (quad9, refine 1, 2, 4) and the 3D
reference on the mirror half (refine 1 with 32 and 64 elements round; ``--fine`` adds SMFEM at
refine 8 and the 3D reference at refine 2 with 64 round: 146k unknowns) against each other (the spatial difference: same step, solver against solver) and
against the harmonic model integrated exactly in time (reference-modal, refine 2, its harmonics
decomposed whole: the total error, time included). Per run: unknowns, CPU, and per probe the
relative max-norm difference.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from cases import get_case
from cases import verification_axis as va
from cases.geometry import RING
from cases.msh_section import read_msh
from smfem.runs import threads
from smfem.runs.registry import solve

PUCK = Path(__file__).resolve().parents[1] / "examples" / "puck_strike.toml"


def timed(solver: str, case):
    t0 = time.process_time()
    run = solve(solver, case)
    if not run.converged:
        raise SystemExit(f"{solver} {case.name}: {run.message}")
    return run, time.process_time() - t0


def orders(errors: list[float]) -> str:
    return " ".join(f"{np.log2(a / b):.2f}" for a, b in zip(errors, errors[1:]))


def manufactured(tiny: bool) -> None:
    with tempfile.TemporaryDirectory() as scratch:
        section = read_msh(va.write(Path(scratch) / "square.msh"), RING)
    base = {"time": "quadratic", "dt": 0.05, "t_end": 0.05 if tiny else 0.25}
    print("manufactured motion through the axis: L2 error at t_end (exact in time)")
    rows = [("reference-3d", {"dim": 3}, (1,) if tiny else (1, 2, 3)),
            ("smfem", {"element": "moment4"}, (1,) if tiny else (1, 2, 4, 8)),
            ("smfem", {"element": "quad9"}, (1,) if tiny else (1, 2, 4, 8))]
    for solver, params, levels in rows:
        errors = []
        for k in levels:
            extra = {"theta_elements": 4 * k} if solver == "reference-3d" else {}
            run, cpu = timed(solver, va.build(section, {**base, **params, **extra, "refine": k}))
            errors.append(run.info["error_l2"])
            print(f"  {solver:13s} {params.get('element', ''):8s} refine {k}: {run.n_dof:7d} unknowns, "
                  f"{cpu:7.2f} CPU s, L2 {errors[-1]:.3e}")
        print(f"  {solver} {params.get('element', '')} orders: {orders(errors)}")


def difference(a, b) -> dict[str, float]:
    """Per probe, ``max |a - b| / max |b|`` over ``b``'s times (``a`` interpolated there)."""
    return {name: float(np.abs(np.interp(b.t, a.t, a.history[name]) - b.history[name]).max()
                        / np.abs(b.history[name]).max()) for name in b.history}


def puck(fine: bool, tiny: bool, halve: bool = False) -> None:
    dt = get_case(PUCK).dt / (2 if halve else 1)
    over = {"dt": dt, **({"t_end": 2 * dt} if tiny else {})}
    runs = {}
    levels = [("smfem-quad9", {"refine": k, "harmonics": h}) for k, h in ((1, 32), (2, 32), (4, 48))]
    # the 3D reference on the half 0 <= theta <= pi (the strike is mirror-symmetric; the whole's
    # histories to 6e-13, tests/test_reference_axis.py): half the unknowns and memory
    levels += [("reference-3d", {"refine": 1, "theta_elements": 32, "mirror": True}),
               ("reference-3d", {"refine": 1, "theta_elements": 64, "mirror": True})]
    if fine:
        levels.insert(3, ("smfem-quad9", {"refine": 8, "harmonics": 48}))
        levels.append(("reference-3d", {"refine": 2, "theta_elements": 64, "mirror": True}))
    levels.append(("reference-modal", {"refine": 2}))
    if tiny:  # eight harmonics: at the scene's 32 the modal run's dense eigenproblems took a third of the test
        levels = [("smfem-quad9", {"refine": 1, "harmonics": 8}),
                  ("reference-3d", {"refine": 1, "theta_elements": 8, "mirror": True}),
                  ("reference-modal", {"refine": 1, "harmonics": 8})]
    print(f"puck_strike ({PUCK.name}), dt {dt:g} s")
    for solver, params in levels:
        run, cpu = timed(solver, get_case(PUCK, {**over, **params}))
        label = f"{solver} " + " ".join(f"{k}={v}" for k, v in params.items())
        runs[label] = run
        print(f"  {label:44s} {run.n_dof:7d} unknowns, {cpu:8.1f} CPU s")
    labels = list(runs)
    judges = [label for label in labels if label.startswith(("reference-3d", "reference-modal"))][-2:]
    for judge in judges:
        kind = "total (exact in time)" if judge.startswith("reference-modal") else "spatial (same dt)"
        print(f"  against {judge}, {kind}: per probe, % of its largest value")
        for label in labels:
            if label != judge:
                d = difference(runs[label], runs[judge])
                print(f"    {label:44s} " + "  ".join(f"{k} {100 * v:6.3f}" for k, v in d.items()))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--manufactured", action="store_true")
    ap.add_argument("--puck", action="store_true")
    ap.add_argument("--fine", action="store_true", help="the puck's 3D reference at refine 2 too (about 8 GB, "
                    "20 CPU min at the scene's step) and SMFEM at refine 8")
    ap.add_argument("--halve", action="store_true", help="the puck's runs at half the scene's step")
    ap.add_argument("--tiny", action="store_true", help="one level, a step or two, eight harmonics on the puck (the tests run it so)")
    args = ap.parse_args(argv)
    threads.pin()
    both = not (args.manufactured or args.puck)
    if args.manufactured or both:
        manufactured(args.tiny)
    if args.puck or both:
        puck(args.fine, args.tiny, args.halve)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
