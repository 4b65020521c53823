"""The 3D reference FEM against a scene's stored truth: the settings that reach 1 % (3 % on the
notched cylinder), their CPU time and memory.

    python benchmarks/reference_3d_to_truth.py [--runs SCENE:REFINE:DT_DIVISOR[:bbar] ...] [--tiny]

Each run: the 3D reference (one BLAS thread, ``linear_solver=auto``) at the scene's window, its
headline error (the largest relative max-norm error over the displacement and velocity probes,
through the scene's comparison window) against ``smfem/truths/SCENE``, its CPU time, the process's
peak memory so far, and the CG iterations on Newton tangents.
"""

from __future__ import annotations

import argparse
import resource

from smfem.runs.threads import pin

pin()

from cases import get_case  # noqa: E402
from smfem.runs.registry import solve  # noqa: E402
from smfem.studies import stored  # noqa: E402
from smfem.studies.metrics import headline_errors  # noqa: E402

#: measured 2026-11-26 (benchmarks/README.md): the cheapest run of each scene within its target
RUNS = ("dome:2:2", "thick_cylinder:3:16", "notched_strip:2:2", "rod_impact:1:2", "notched_cylinder:3:2:bbar")


def measure(item: str, sets: dict | None = None) -> dict:
    name, refine, divisor, *flags = item.split(":")
    truth = stored.read(stored.directory(name))
    base = get_case(name)
    case = get_case(name, {"dim": 3, "refine": int(refine), "dt": base.dt / float(divisor), **(sets or {})})
    result = solve("reference", case, options={"bbar": "bbar" in flags})
    errors = headline_errors(case, truth, result.t, result.history)
    return {"run": item, "n_dof": result.n_dof, "cpu_s": result.cpu_time_s, "error": max(errors.values()),
            "worst": max(errors, key=errors.get), "cg": result.info.get("cg_iterations", 0),
            "peak_GB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", nargs="*", default=RUNS, help="scene:refine:dt divisor[:bbar]")
    parser.add_argument("--tiny", action="store_true", help="the 3D thick cylinder r1 over 10 steps")
    args = parser.parse_args(argv)
    runs, sets = (["thick_cylinder:1:1"], {"t_end": 4e-4}) if args.tiny else (args.runs, None)
    print(f"{'run':28} {'dofs':>7} {'CPU s':>8} {'error %':>8} {'worst':>8} {'CG its':>7} {'peak GB':>7}")
    for item in runs:
        r = measure(item, sets)
        print(f"{r['run']:28} {r['n_dof']:7d} {r['cpu_s']:8.1f} {100 * r['error']:8.2f} {r['worst']:>8} {r['cg']:7d} "
              f"{r['peak_GB']:7.2f}", flush=True)


if __name__ == "__main__":
    main()
