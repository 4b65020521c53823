"""SMFEM's contact layer over section kinds and elements (issue 56): the rod against the wall and
the colliding rods, each on its mapped blocks and on its gmsh section, with moment4 and quad9.

    python benchmarks/contact_sections.py [--csv PATH]   # about 6 CPU min
    python benchmarks/contact_sections.py --scenes rod_collision --elements quad9 --refine 1

Scenes: ``rod_impact`` (mapped) and ``examples/rod_impact_unstructured.toml`` (gmsh), the rod
against the rigid wall; ``rod_collision`` (mapped) and ``examples/rod_collision_unstructured.toml``
(gmsh: two bodies in one section), the colliding rods, at nu = 0.3 and at nu = 0. Each with
element moment4 and quad9, at dt, dt / 2, dt / 4 (the scene's dt is 1e-6 s) and refine 1 and 2.

Per run: whether it ran to the end (converged, its last step at t_end: no exit), the energy
balance (info ``energy_before`` / ``energy_after``, relative change; the contact layer rejects a
gain above :data:`smfem.contact.ENERGY_GAIN_LIMIT`), CPU (one run, one BLAS thread, model built
and solved, after a warm-up run), and the error: at nu = 0.3 the headline (the displacement and
velocity probes through the 2R/c window, :func:`smfem.studies.metrics.headline_error`) against
the stored truth (``smfem/truths/NAME``, made on the mapped scene: the same bodies, so it judges
both sections); for the collision at nu = 0 the 1-D answer's
(:func:`cases.rod_collision.collision_histories`): the velocities' and the end displacement's
windowed max-norm, the stress pulses' level and duration (:func:`cases.rod_collision.pulse_errors`).
"""

from __future__ import annotations

import argparse
import csv
import itertools
import math
import time
from pathlib import Path

from cases import get_case
from cases.rod_collision import collision_histories, pulse_errors
from smfem.runs import threads
from smfem.runs.errors import history_errors
from smfem.runs.registry import SMFEM, solve
from smfem.studies import metrics
from smfem.studies.stored import directory, read

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
#: scene -> its sources by section kind
SECTIONS = {name: {"mapped": name, "gmsh": str(EXAMPLES / f"{name}_unstructured.toml")}
            for name in ("rod_impact", "rod_collision")}
#: the poisson ratios each scene runs at: the collision also at nu = 0, where the 1-D answer is exact
NUS = {"rod_impact": (None,), "rod_collision": (None, 0.0)}
ELEMENTS, DIVISORS, REFINES = ("moment4", "quad9"), (1, 2, 4), (1, 2)
#: --tiny: a few steps at the smallest dt (dt / 4 = 2.5e-7 s)
TINY_T_END = 1.25e-6
#: the 1-D answer's probes compared by max-norm (the stresses by their pulses)
THEORY_PROBES = ("striker_vz", "target_vz", "target_end_uz")
COLUMNS = ("scene", "section", "element", "refine", "dt", "nu", "converged", "to_end", "message",
           "energy_change", "cpu_s", "dof", "vs_truth", "striker_vz", "target_vz", "target_end_uz",
           "contact_p_level", "contact_p_duration", "target_mid_szz_level", "target_mid_szz_duration")


def run(scene: str, section: str, element: str, refine: int, divisor: int, nu=None, t_end=None,
        truth=None) -> dict:
    """One run of the matrix: a row of :data:`COLUMNS`; its errors against ``truth`` where given,
    against the 1-D answer for the collision at nu = 0 run to the scene's end."""
    base = get_case(scene)
    sets = {"element": element, "refine": refine, "dt": base.dt / divisor}
    sets |= {} if nu is None else {"nu": nu}
    sets |= {} if t_end is None else {"t_end": t_end}
    case = get_case(SECTIONS[scene][section], sets)
    t0 = time.process_time()
    r = solve(SMFEM, case)
    cpu = time.process_time() - t0
    row = dict.fromkeys(COLUMNS, math.nan) | {
        "scene": scene, "section": section, "element": element, "refine": refine, "dt": case.dt,
        "nu": case.material.nu, "converged": bool(r.converged), "message": r.message or "",
        "to_end": bool(len(r.t) and r.t[-1] >= case.t_end - 0.5 * case.dt), "cpu_s": cpu,
        "dof": r.n_dof, "energy_change": r.info["energy_after"] / r.info["energy_before"] - 1}
    if truth is not None:
        row["vs_truth"] = metrics.headline_error(case, truth, r.t, r.history)
    if scene == "rod_collision" and case.material.nu == 0.0 and t_end is None:
        E, rho, v0 = case.material.E, case.material.rho, case.params["v0"]
        window = case.references["comparison_window_s"]
        exact = collision_histories(r.t, E, rho, v0)
        row |= {name: history_errors(r.t, r.history[name], r.t, exact[name], window)[0]
                for name in THEORY_PROBES}
        row |= pulse_errors(r.t, r.history, E, rho, v0, window)
    return row


def matrix(scenes=tuple(SECTIONS), sections=("mapped", "gmsh"), elements=ELEMENTS,
           divisors=DIVISORS, refines=REFINES, t_end=None, echo=None) -> list[dict]:
    """Every run of the matrix (:func:`run`), scene by scene, section, nu, element, refine, dt;
    ``t_end``: shorter runs, judged against nothing; ``echo``: called with each row as it is made."""
    rows = []
    for scene in scenes:
        truth = read(directory(scene)) if t_end is None else None
        for section, nu, element, refine, divisor in itertools.product(sections, NUS[scene], elements,
                                                                        refines, divisors):
            rows.append(run(scene, section, element, refine, divisor, nu, t_end, truth if nu is None else None))
            if echo:
                echo(rows[-1])
    return rows


#: the printed table's columns: heading, row key, format (the 1-D velocities: the larger of the two)
TABLE = (("energy", "energy_change", "+9.1e"), ("CPU s", "cpu_s", "6.2f"), ("vs truth", "vs_truth", "8.2e"),
         ("1-D: v", "velocities", "8.2e"), ("end_uz", "target_end_uz", "8.2e"),
         ("p level", "contact_p_level", "+8.1e"), ("p dur", "contact_p_duration", "+8.1e"),
         ("mid lev", "target_mid_szz_level", "+8.1e"), ("mid dur", "target_mid_szz_duration", "+8.1e"))
HEADER = (f"{'scene':14s} {'section':7s} {'element':7s} r  {'dt':7s}  nu   end  "
          + "  ".join(f"{name:>{len(format(1.0, fmt))}s}" for name, _, fmt in TABLE))


def line(row: dict) -> str:
    """One row of the printed table (``-`` where a run has no such figure)."""
    row = row | {"velocities": max(row["striker_vz"], row["target_vz"])}
    cells = [format(row[key], fmt) if math.isfinite(row[key]) else "-".rjust(len(format(1.0, fmt)))
             for _, key, fmt in TABLE]
    end = "yes" if row["converged"] and row["to_end"] else "NO "
    return (f"{row['scene']:14s} {row['section']:7s} {row['element']:7s} {row['refine']}  {row['dt']:.1e}  "
            f"{row['nu']:.1f}  {end}  " + "  ".join(cells) + (f"  {row['message']}" if row["message"] else ""))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", nargs="+", choices=tuple(SECTIONS), default=list(SECTIONS))
    ap.add_argument("--elements", nargs="+", choices=ELEMENTS, default=list(ELEMENTS))
    ap.add_argument("--divisors", nargs="+", type=int, default=list(DIVISORS),
                    help="dt = the scene's dt / each")
    ap.add_argument("--refine", nargs="+", type=int, default=list(REFINES))
    ap.add_argument("--csv", type=Path, metavar="PATH", help="also write the table as CSV")
    ap.add_argument("--tiny", action="store_true",
                    help="a few steps of the gmsh sections with quad9 (the tests run it so)")
    args = ap.parse_args(argv)
    threads.pin()
    print(HEADER)
    settings = dict(scenes=args.scenes, elements=args.elements, divisors=args.divisors, refines=args.refine)
    if args.tiny:
        settings = dict(sections=("gmsh",), elements=("quad9",), divisors=(4,), refines=(1,), t_end=TINY_T_END)
    scene = settings.get("scenes", tuple(SECTIONS))[0]
    for element in settings["elements"]:  # a process's first run pays its imports and caches: no row's
        run(scene, "mapped", element, 1, 1, t_end=2 * get_case(scene).dt)
    rows = matrix(**settings, echo=lambda row: print(line(row), flush=True))
    if args.csv:
        with args.csv.open("w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=COLUMNS)
            writer.writeheader()
            writer.writerows(rows)
        print(f"written to {args.csv}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
