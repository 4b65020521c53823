"""CalculiX's procedures against the stored truths: the cheapest procedure and mesh that reaches
a target (1 %; 5 % on the notched cylinder).

    python benchmarks/calculix_procedures.py [--budget S] [--procedures P ...] [--tiny] [SCENE ...]

Per scene, each procedure that takes it (of ``--procedures``, default all) runs its ladder
cheapest first (as a study's carried series, ``smfem.studies.ladder``): ``explicit`` and
``modal`` over the full plan's levels (``smfem.studies.plan.CCX_EXPLICIT``, ``CCX_MODAL``: meshes,
and meshes x modes), ``implicit`` over the meshes at dt, dt / 2, dt / 4; a ladder stops at the target, or before a run
whose predicted CPU time passes ``--budget`` (default 300 s), or when its last run took more
than that. One line per run: procedure, level, headline error against the stored truth
(``smfem.studies.metrics.headline_error``), ccx's CPU time. A refused procedure prints its one
line. ``--tiny``: the dome over the tiny report's window (:data:`TINY_WINDOW`), each ladder's
first level. Needs ``ccx`` on PATH (without it, one line says so).
"""

from __future__ import annotations

import argparse
import math

from cases import UnsupportedCase, get_case
from cases.params import ToolMissing
from smfem.api import truth as stored_truth
from smfem.runs.registry import CALCULIX, CALCULIX_MODAL, solve, split_level
from smfem.studies.metrics import headline_error
from smfem.studies.plan import CCX_EXPLICIT, CCX_MODAL

PROCEDURES = ("explicit", "modal", "implicit")
SCENES = ("thick_cylinder", "dome", "notched_strip", "layered_cylinder", "layered_cylinder_pulse", "moving_load",
          "notched_cylinder")
#: the target per scene (the notched cylinder's truth and meshes: 5 %, as the issue says)
TARGET = {"notched_cylinder": 0.05}
#: ``--tiny``'s window: the tiny report's dome (tests/test_report.py), eight of the scene's steps (over
#: the scene's own window ccx's implicit procedure took 12 CPU s of the test's 16)
TINY_WINDOW = {"t_end": 4e-5}
#: procedures not run, with the measured reason
SKIP = {("dome", "explicit"): "CAX4 is expanded into 2-degree wedges whose width vanishes at the axis: ccx's "
                              "Courant increment is 1.4e-8 s (dt / 350), 322 CPU s at refine 1 for 30 %"}


def ladders(name: str) -> dict[str, list[dict]]:
    """Per procedure its levels, cheapest first (by :func:`work`): ``(case overrides, options)``."""
    dt = get_case(name).dt
    levels = {
        "explicit": [(level, {}) for level in CCX_EXPLICIT],
        "modal": [split_level(CALCULIX_MODAL, level) for level in CCX_MODAL],
        "implicit": [({"refine": r, "dt": dt / d}, {}) for r in (1, 2) for d in (1, 2, 4)],
    }
    return {p: sorted(ls, key=lambda level: work(name, p, *level)) for p, ls in levels.items()}


def work(name: str, procedure: str, overrides: dict, options: dict) -> float:
    """What a run's CPU time grows with: explicit, ccx's increment shrinks with the mesh; modal,
    the eigen-solve grows about as the square of the modes."""
    case = get_case(name, overrides)
    return case.n_steps * case.refine ** (3 if procedure == "explicit" else 2) * options.get("modes", 1) ** 2


def measure(name: str, budget: float, procedures, first_only: bool = False, window: dict | None = None) -> None:
    """``first_only``: each ladder's first level; ``window``: case overrides of every run (its window)."""
    truth = stored_truth(name)
    target = TARGET.get(name, 0.01)
    print(f"\n{name}: target {100 * target:g} %", flush=True)
    for procedure, levels in ladders(name).items():
        if procedure not in procedures:
            continue
        if (name, procedure) in SKIP:
            print(f"  {procedure:9s} not run: {SKIP[name, procedure]}", flush=True)
            continue
        last_cpu, last_work = None, None
        for overrides, options in levels[:1] if first_only else levels:
            case, level_work = get_case(name, {**overrides, **(window or {})}), work(name, procedure, overrides, options)
            if last_cpu is not None and last_cpu * level_work / last_work > budget:
                print(f"  {procedure:9s} {_level(overrides, options):24s} skipped: predicted "
                      f"{last_cpu * level_work / last_work:.3g} CPU s > {budget:g}", flush=True)
                break
            try:
                run = solve(CALCULIX, case, options={"procedure": procedure, **options})
            except UnsupportedCase as exc:
                print(f"  {procedure:9s} refused: {exc}", flush=True)
                if "modes=" in str(exc):  # too many modes for this mesh: the next mesh may take them
                    continue
                break
            error = headline_error(case, truth, run.t, run.history) if run.converged else math.nan
            print(f"  {procedure:9s} {_level(overrides, options):24s} error {100 * error:7.3g} %  "
                  f"CPU {run.cpu_time_s:8.3g} s  {run.info.get('element')}  {run.message}", flush=True)
            last_cpu, last_work = run.cpu_time_s, level_work
            if error <= target or run.cpu_time_s > budget:
                break


def _level(overrides: dict, options: dict) -> str:
    return " ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}" for k, v in {**overrides, **options}.items())


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", default=SCENES)
    parser.add_argument("--budget", type=float, default=300.0, help="CPU seconds a run may take (default 300)")
    parser.add_argument("--procedures", nargs="+", default=PROCEDURES, choices=PROCEDURES,
                        help="the procedures to run (default all)")
    parser.add_argument("--tiny", action="store_true", help="the dome over a short window, each ladder's first level")
    args = parser.parse_args(argv)
    try:
        for name in ("dome",) if args.tiny else args.scenes:
            measure(name, args.budget, args.procedures, first_only=args.tiny, window=TINY_WINDOW if args.tiny else None)
    except ToolMissing as exc:
        print(f"\n{exc}\n(nothing measured)")


if __name__ == "__main__":
    main()
