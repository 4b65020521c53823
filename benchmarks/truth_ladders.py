"""Explicit truth ladders: how the variants of the reference converge on a scene.

    python benchmarks/truth_ladders.py [--case notched_cylinder] [--variants standard bbar graded]
                                       [--coarse] [--cache out/truth-runs]

For each variant of the explicit reference (the standard quadratic element, its B-bar form,
the standard one on meshes graded toward the cut-outs' corners with exponent 2) it assembles
the explicit truth over r2, r4, r8 with the r3, r6 pair (graded: r1, r2 only, its steps are
many times shorter) and prints per probe the observed order, the size of Richardson's
correction and the truth's uncertainty; then the distance between the variants' truths and
from each to the stored truth (``smfem/truths/CASE``); and the time error of central differences at half the
critical step on r2 (the same mesh at a quarter of it). It shares the run cache of
``smfem truth --full`` (``out/truth-runs``): runs made by the same code are reused, so right
after the stored truths only the graded runs and the time check are new (about 25 CPU
minutes for the notched cylinder; the whole set about 3 hours from an empty cache).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from cases import get_case
from smfem.studies.cache import RunCache
from smfem.studies.jobs import Job
from smfem.studies.stored import directory, read
from smfem.studies.plan import EXPLICIT, EXPLICIT_TRUTH, TruthPlan, explicit_truth
from smfem.studies.study import run_cached
from smfem.studies.truth import assemble, jobs
from smfem.runs.errors import history_errors

VARIANTS = {"standard": {}, "bbar": {"bbar": True}, "graded": {"grading": 2.0}}


def plan_of(variant: str, tiny: bool, coarse: bool = False) -> TruthPlan:
    plan = explicit_truth(**VARIANTS[variant])
    if variant == "graded" or tiny or coarse:
        # coarse: the uniform meshes one level further than the graded, at about its CPU; tiny:
        # two meshes (the tests run it so: r4's explicit steps took 30 of its 40 s)
        levels = (1, 2, 4) if coarse and variant != "graded" and not tiny else (1, 2)
        return TruthPlan(EXPLICIT_TRUTH, refine=levels, solver=EXPLICIT, options=plan.options)
    return plan


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="notched_cylinder")
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--cache", default="out/truth-runs")
    parser.add_argument("--coarse", action="store_true",
                        help="the uniform variants on r1, r2, r4, the graded on r1, r2 (its r2 costs about a uniform r4): minutes")
    parser.add_argument("--tiny", action="store_true", help="a few steps of the smallest settings (the tests run every benchmark so)")
    args = parser.parse_args(argv)
    name = args.case
    base = {"t_end": 3 * get_case(name).dt} if args.tiny else {}
    cache = RunCache(Path(args.cache))
    truths = {}
    for variant in args.variants:
        plan = plan_of(variant, args.tiny, args.coarse)
        wanted = jobs(name, plan, base)
        runs, _, _ = run_cached(list(wanted.values()), cache, workers=2, progress=False)
        truth = assemble(name, plan, base, {role: runs[j] for role, j in wanted.items()})
        truths[variant] = truth
        cpu = sum(r.summary["cpu_time_s"] for r in runs.values())
        print(f"{variant}: {truth.name} (CPU {cpu:.0f} s)")
        for probe, part in truth.parts.items():
            extra = f", Richardson moved it {100 * part['extrapolation']:.3g} %" if "extrapolation" in part else ""
            print(f"  {probe:<11} order {part['order_space']:.2f}, {part['estimate']}{extra}, "
                  f"uncertainty {100 * truth.uncertainty[probe]:.3g} %")
    case = get_case(name, base)
    window = case.references.get("comparison_window_s", 0.0)
    variants = list(truths)
    pairs = [(f"{a} against {b}", truths[a], truths[b]) for a, b in zip(variants, variants[1:])]
    if not args.tiny:
        stored_truth = read(directory(name))
        pairs += [(f"{v} against the stored truth", truths[v], stored_truth) for v in variants]
    for label, a, b in pairs:
        distance = {p: history_errors(b.t, b.values[p], a.t, a.values[p], window)[0]
                    for p in case.probe_names if not p.startswith("peps")}
        print(f"{label}: " + ", ".join(f"{p} {100 * d:.3g} %" for p, d in distance.items()))
    level = 1 if args.tiny else 2
    sample = {**base, "dt": case.dt / 16, "refine": level}
    pair = [Job.make(name, EXPLICIT, sample, options={"step_divisor": d} if d > 1 else None) for d in (1, 2)]
    runs, _, _ = run_cached(pair, cache, workers=2, progress=False)
    half, quarter = (runs[j].history for j in pair)
    differences = {p: history_errors(half.t.to_numpy(), half[p].to_numpy(), quarter.t.to_numpy(),
                                     quarter[p].to_numpy(), window)[0] for p in case.probe_names}
    print(f"time error at r{level}: half against a quarter of the critical step: "
          + ", ".join(f"{p} {100 * d:.3g} %" for p, d in differences.items()))


if __name__ == "__main__":
    from smfem.runs import threads

    threads.pin()  # one BLAS thread, as in smfem's own entry points
    main()
