"""Peak memory and CPU of SMFEM's decoupled harmonics marched in batches (smfem/batched.py).

    python benchmarks/decoupled_memory.py [--harmonics 24 64] [--refine 2] [--scan] [--tiny]

Each run in a child process of its own, so that its peak resident memory is its own (the
child's high-water mark) and one run's heap does not carry into the next; one BLAS thread.
The headline: the flywheel, 9-node element, ``time_scheme=gauss``, at ``--refine`` and each of
``--harmonics`` with the default batch memory. ``--scan``: the batch size against CPU (the
option ``batch_memory_mb`` from one harmonic a batch to all in one) on the flywheel at refine 1,
8 harmonics, both time schemes, and on the moving load (60 small harmonics), where many batches
cost their bookkeeping per step.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

#: what a child runs: ``CHILD scene params options`` -> one JSON line
CHILD = """
import json, resource, sys, time
from smfem.runs import threads
threads.pin()
from cases import get_case
from smfem.options import SolverOptions
from smfem.solver import solve
scene, params, options = sys.argv[1], json.loads(sys.argv[2]), json.loads(sys.argv[3])
case = get_case(scene, params)
cpu = time.process_time()
result = solve(case, SolverOptions(**options), with_fields=False)
print(json.dumps({"cpu_s": time.process_time() - cpu, "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "n_dof": result.n_dof, "batches": result.info.get("batches"), "predicted_mb": result.info.get("batch_memory_mb")}))
"""


def run(scene: str, params: dict, options: dict | None = None) -> dict:
    """One run in a child process: CPU s (the solve), peak resident MB (2^20 bytes), dof, the
    batches and the largest batch's predicted MB."""
    out = subprocess.run([sys.executable, "-c", CHILD, scene, json.dumps(params), json.dumps(options or {})],
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.splitlines()[-1])


def line(label: str, r: dict) -> str:
    batches = r["batches"] or []
    return (f"{label}: {r['n_dof']} dof, cpu {r['cpu_s']:.1f} s, peak {r['peak_mb']:.0f} MB, batches of "
            f"{'/'.join(map(str, sorted(set(batches), reverse=True)))} harmonics ({len(batches)}; the largest "
            f"predicted at {r['predicted_mb']} MB)")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--harmonics", type=int, nargs="+", default=[24, 64])
    ap.add_argument("--refine", type=int, default=2)
    ap.add_argument("--scan", action="store_true", help="batch size against CPU instead of the headline")
    ap.add_argument("--tiny", action="store_true", help="a few steps of the smallest settings (the tests run every benchmark so)")
    args = ap.parse_args(argv)
    base = {"element": "quad9", "time_scheme": "gauss"}
    if args.tiny:
        base, args.harmonics, args.refine = dict(base, t_end=1e-4), [1, 2], 1
    if not args.scan:
        for n in args.harmonics:
            r = run("flywheel", dict(base, refine=args.refine, harmonics=n))
            print(line(f"flywheel quad9 gauss refine {args.refine} harmonics {n}", r))
        return
    caps = [1.0, 16.0, 64.0, 256.0, 1e4]
    runs = [("flywheel", dict(base, refine=1, harmonics=8), caps),
            ("flywheel", dict(base, refine=1, harmonics=8, time_scheme="newmark"), caps),
            ("moving_load", {"plastic": False}, [1e-3, 1.0, 16.0])]
    for scene, params, scene_caps in runs:
        for cap in scene_caps:
            print(line(f"{scene} {params} batch_memory_mb={cap:g}", run(scene, params, {"batch_memory_mb": cap})))


if __name__ == "__main__":
    main()
