"""The rod impact with each section element of SMFEM's contact layer: moment4 (4-node layer
elements on 2-node face segments) and quad9 (6-node layer elements, quadratic along the face).

    python benchmarks/contact_elements.py            # about 1 CPU min
    python benchmarks/contact_elements.py --tilted   # also the tilted wall with friction against the 3D reference (+1 min)

Per run: size, CPU, state iterations per step (mean / max), the steps in contact with part of
the face open (inside the contact window) and the reversals of the closed share (chatter),
the energy change; the headline error (displacement and velocity probes, relative max-norm
through the 2R/c window) and the stress probes' against the stored truth (``smfem/truths/rod_impact``,
:func:`smfem.studies.stored.find`) and against the reference 2D at refine 2 (same dt).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from cases import get_case
from reference_fem import solve as reference
from smfem.runs.errors import history_errors
from smfem.solver import solve as smfem

#: (solver, element, refine); the reference runs in the case's dim, 2 (axisymmetric) here
RUNS = [("smfem", "moment4", 1), ("smfem", "moment4", 2), ("smfem", "moment4", 4),
        ("smfem", "quad9", 1), ("smfem", "quad9", 2), ("smfem", "quad9", 4),
        ("reference-2d", "", 1), ("reference-2d", "", 2)]


def errors(case, run, against_t, against) -> tuple[float, float]:
    """(headline, stress): the largest windowed relative max-norm over the u, v probes and over
    the stress probes."""
    window = case.references["comparison_window_s"]
    e = {p.name: history_errors(run.t, run.history[p.name], against_t, against[p.name], window)[0]
         for p in case.probes}
    return (max(e[p.name] for p in case.probes if p.field in ("u", "v")),
            max(e[p.name] for p in case.probes if p.field == "sigma"))


def contact_facts(run) -> str:
    """Steps with the face partly open inside the contact window, reversals of the closed share."""
    closed = np.array(run.info.get("closed_fraction", [np.nan]))
    window = run.info.get("contact_window")
    if window is None:
        return "no contact"
    inside = closed[int(round(window[0] / run.t[1])):int(round(window[1] / run.t[1])) + 1]
    steps = np.diff(inside)
    steps = steps[steps != 0]
    reversals = int(np.sum(np.sign(steps[1:]) != np.sign(steps[:-1])))
    change = run.info["energy_after"] / run.info["energy_before"] - 1
    return f"partly open {int(np.sum((inside > 0) & (inside < 1))):4d}, reversals {reversals:3d}, energy {change:+.1e}"


def rod(args):
    sets = {"t_end": 5e-6} if args.tiny else {}
    truth, why = None, "not looked up (--tiny)"
    if not args.tiny:
        from smfem.studies.stored import find
        from smfem.studies.truth import plan_for

        truth, why = find("rod_impact", get_case("rod_impact"), plan_for("rod_impact", {}, "full"))
    if truth is None:
        print(f"no truth: {why}")
    results = []
    for solver, element, refine in RUNS[3:4] if args.tiny else RUNS:
        case = get_case("rod_impact", {"refine": refine, **({"element": element} if element else {}), **sets})
        t0 = time.process_time()
        r = smfem(case, with_fields=False) if solver == "smfem" else reference(case)
        results.append((solver, element, refine, case, r, time.process_time() - t0))
    finest = next((r for solver, _, refine, _, r, _ in results if solver == "reference-2d" and refine == 2), None)
    print("run                     dof     cpu s  it mean/max  vs truth: u,v  sigma   vs ref-2d r2: u,v  sigma   contact")
    for solver, element, refine, case, r, cpu in results:
        e_truth = errors(case, r, truth.t, truth.values) if truth is not None else (np.nan, np.nan)
        e_ref = errors(case, r, finest.t, finest.history) if finest is not None else (np.nan, np.nan)
        its = f"{r.info['iterations_mean']:.3f}/{r.info['iterations_max']}" if solver == "smfem" else "-"
        print(f"{solver + ' ' + element:20s} r{refine} {r.n_dof:6d} {cpu:7.2f}  {its:11s}  {e_truth[0]:9.2e} {e_truth[1]:8.2e}"
              f"  {e_ref[0]:12.2e} {e_ref[1]:8.2e}   {contact_facts(r) if solver == 'smfem' else ''}")


def tilted(args):
    """The rod on a wall tilted by 0.01 with friction 0.3 (6 harmonics): both elements against the
    3D reference at refine 1 (its slow test, tests/test_tilted_wall.py)."""
    sets = {"wall_slope": 0.01, "friction": 0.3, "harmonics": 6, **({"t_end": 1e-5} if args.tiny else {})}
    t0 = time.process_time()
    ref = reference(get_case("rod_impact", dict(sets, dim=3)))
    print(f"tilted wall, friction 0.3: reference 3D r1 {ref.n_dof} dof, cpu {time.process_time() - t0:.1f} s, "
          f"energy lost {1 - ref.info['energy_after'] / ref.info['energy_before']:.2%}")
    for element in ("moment4", "quad9"):
        case = get_case("rod_impact", dict(sets, element=element))
        t0 = time.process_time()
        s = smfem(case, with_fields=False)
        cpu = time.process_time() - t0
        window = case.references["comparison_window_s"]
        cells = [f"{p} {history_errors(s.t, a, ref.t, ref.history[p], window)[0]:.1%}" for p, a in s.history.items()]
        print(f"  {element}: {s.n_dof} dof, cpu {cpu:.2f} s, iterations {s.info['iterations_mean']:.2f}/"
              f"{s.info['iterations_max']}, energy lost {1 - s.info['energy_after'] / s.info['energy_before']:.2%}; "
              f"through 2R/c: " + ", ".join(cells))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tilted", action="store_true", help="also the tilted wall with friction against the 3D reference")
    ap.add_argument("--tiny", action="store_true", help="a few steps of the smallest settings (the tests run every benchmark so)")
    args = ap.parse_args(argv)
    rod(args)
    if args.tilted:
        tilted(args)


if __name__ == "__main__":
    from smfem.runs import threads

    threads.pin()  # one BLAS thread, as in smfem's own entry points
    main()
