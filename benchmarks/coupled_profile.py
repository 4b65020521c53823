"""Where SMFEM's time goes on the scenes whose harmonics couple, against the bare solves.

    python benchmarks/coupled_profile.py [--scenes NAME ...] [--set NAME:KEY=VALUE ...] [--forms] [--tiny]

For each scene at its cheapest settings within 1 % of its truth in the latest full study (3 %
on the notched cylinder, which SMFEM does not bring to 1 %): the run's CPU (one thread, no
profiler), then one run under cProfile, its time split into model build, system set-up
(factorizations, the Woodbury capacitance), and the march: the block-diagonal factors'
triangular solves, the Woodbury correction around them, the elastic operator applied (``K x``,
``M x``), stresses synthesized at the x3 points, the material law, forces projected back,
probes, the rest. The split is of the profiled run, scaled to the plain run's CPU. Last, the
bare solves, each timed alone (the least of 30) times the run's iterations (an elastic step is
one): one solve with the block-diagonal factors of the body without its cut-outs (what a step
would cost if the harmonics did not couple), and one with the coupled form the run chooses
(whole, Woodbury: the least a step of this discretization can cost, the limit); the ratios of
the run's CPU to them are what the method's overhead costs.

Imports (``python -c 'import smfem.solver'``) are listed apart: every entry point pays them once.

``--forms``: the forms of the coupled solve (:mod:`smfem.coupled_solve`) side by side on the
elastic notched scenes, each run forced to one form: CPU (the least of two), the predicted flops
of the run, and which form the prediction chooses.
"""

from __future__ import annotations

import argparse
import cProfile
import os
import pstats
import subprocess
import sys
import time
from functools import partial

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from cases import get_case  # noqa: E402
from smfem.linalg import factorize_spd, stacked_step  # noqa: E402
from smfem.newmark import Constants  # noqa: E402
from smfem.solver import solve  # noqa: E402

#: scene -> the cheapest SMFEM settings within 1 % (3 %: notched cylinder) of its truth in the
#: latest full study (docs/verification.md)
SCENES = {
    "moving_load_notched": {"element": "quad9", "harmonics": 480},
    "moving_load": {"harmonics": 20, "dt": 4e-6},
    "notched_strip": {"harmonics": 120},
    "notched_cylinder": {"refine": 8, "harmonics": 160, "bbar": True},
}
TINY = {"moving_load_notched": {"harmonics": 40, "t_end": 2e-5}, "moving_load": {"t_end": 2e-5},
        "notched_strip": {"harmonics": 40, "t_end": 3.2e-5}, "notched_cylinder": {"refine": 1, "harmonics": 20, "t_end": 5e-4}}
OPTIONS = ("bbar", "iteration_matrix", "direct_max_nonzeros", "x3_oversampling")

#: (category, functions whose cumulative time it is, as (file suffix, function name))
PARTS = (
    ("model", (("smfem/model.py", "__init__"),)),
    ("system set-up", (("smfem/strategy.py", "choose"), ("smfem/strategy.py", "build"))),
    ("march", (("smfem/newmark.py", "march"), ("smfem/gauss.py", "march"))),
    ("triangular solves", (("smfem/linalg.py", "solve"), ("~", "<method 'solve' of 'SuperLU' objects>"))),
    ("woodbury", (("smfem/woodbury.py", "solve"),)),
    ("K x, M x", (("smfem/coupling.py", "K"), ("smfem/coupling.py", "M"))),
    ("synthesis", (("smfem/sampling.py", "stress"),)),
    ("law", (("smfem/laws.py", "stress"),)),
    ("projection", (("smfem/sampling.py", "forces"), ("smfem/sampling.py", "forces_at"))),
    ("probes", (("smfem/probes.py", "values"),)),
)


def cumulative(stats: pstats.Stats, functions) -> tuple[float, int]:
    """Cumulative seconds and calls of the functions, summed."""
    seconds, calls = 0.0, 0
    for (path, _, name), (_, nc, _, ct, _) in stats.stats.items():
        if any(path.endswith(suffix) and name == fname for suffix, fname in functions):
            seconds, calls = seconds + ct, calls + nc
    return seconds, calls


def cumulative_from(stats: pstats.Stats, functions, caller) -> float:
    """Cumulative seconds of the functions in their calls from ``caller`` (file suffix, name)."""
    seconds = 0.0
    for (path, _, name), (_, _, _, _, callers) in stats.stats.items():
        if any(path.endswith(suffix) and name == fname for suffix, fname in functions):
            seconds += sum(v[3] for (cpath, _, cname), v in callers.items()
                           if cpath.endswith(caller[0]) and cname == caller[1])
    return seconds


def split(case_name: str, sets: dict) -> tuple[dict, dict]:
    """Case parameters and solver options of one scene's settings."""
    return ({k: v for k, v in sets.items() if k not in OPTIONS}, {k: v for k, v in sets.items() if k in OPTIONS})


def least_seconds(f, repeats: int = 30) -> float:
    """The least CPU seconds of ``repeats`` calls of ``f``."""
    best = float("inf")
    for _ in range(repeats):
        t0 = time.process_time()
        f()
        best = min(best, time.process_time() - t0)
    return best


def bare_solve_seconds(case, options) -> tuple[float, float]:
    """One solve of the step matrix, alone (the least of 30): with the block-diagonal factors of
    the body without its cut-outs (what a step would cost if the harmonics did not couple), and
    with the coupled form the run chooses (:mod:`smfem.coupled_solve`: what a step of this
    discretization needs at least)."""
    from smfem import coupled_solve
    from smfem.model import Model
    from smfem.strategy import ITERATIONS_PER_STEP

    model = Model(case, nonlinear=case.material.plastic, bbar=options.bbar)  # the modes the run keeps
    a0 = Constants.of(case.dt).a0
    blocks = model.homogeneous_blocks if model.coupling else [(s.K, s.M) for s in model.systems]
    lu = factorize_spd(stacked_step(blocks, a0))
    b = np.random.default_rng(0).normal(size=model.n_dof)
    solves = case.n_steps * (ITERATIONS_PER_STEP if case.material.plastic else 1)
    form, _ = coupled_solve.choose(model, solves, options.direct_max_nonzeros)
    coupled = coupled_solve.build(form, model, a0)
    return least_seconds(partial(lu.solve, b)), least_seconds(partial(coupled.solve, b))


def profile(name: str, sets: dict) -> dict:
    from smfem.options import SolverOptions

    params, opts = split(name, sets)
    case = get_case(name, params)
    options = SolverOptions(**opts)
    t0 = time.process_time()
    plain = solve(case, options, with_fields=False)
    cpu = time.process_time() - t0
    profiler = cProfile.Profile(time.process_time)
    profiler.enable()
    profiled = solve(case, options, with_fields=False)
    profiler.disable()
    stats = pstats.Stats(profiler)
    whole = cumulative(stats, (("smfem/solver.py", "solve"),))[0]
    row = {"scene": name, "settings": " ".join(f"{k}={v}" for k, v in sets.items()), "n_dof": plain.n_dof,
           "solve": plain.info["solve"], "cpu_s": cpu}
    for part, functions in PARTS:
        row[part] = cumulative(stats, functions)[0] * cpu / whole
    row["system set-up"] -= row["model"]  # the strategy builds the model first
    batched = cumulative(stats, (("smfem/batched.py", "solve"),))[0] * cpu / whole
    if batched:  # a batched march builds its systems batch by batch, inside it
        row["system set-up"], row["march"] = 0.0, batched - row["model"]
    row["woodbury"] -= cumulative_from(stats, PARTS[3][1], ("smfem/woodbury.py", "solve")) * cpu / whole
    # forces_at calls forces where many points yield: that time once
    row["projection"] -= cumulative_from(stats, (("smfem/sampling.py", "forces"),),
                                         ("smfem/sampling.py", "forces_at")) * cpu / whole
    iterations = int(np.sum(profiled.iterations)) if getattr(profiled, "iterations", None) is not None else 0
    iterations = iterations or int(round(plain.info["iterations_mean"] * (len(plain.t) - 1))) or (len(plain.t) - 1)
    row["iterations"] = iterations
    block, coupled = bare_solve_seconds(case, options)
    row["bare_solves_s"], row["coupled_solves_s"] = block * iterations, coupled * iterations
    row["cpu_over_bare"], row["cpu_over_coupled"] = cpu / row["bare_solves_s"], cpu / row["coupled_solves_s"]
    return row


#: elastic runs whose harmonics couple, for ``--forms``
FORM_RUNS = (("moving_load_notched", {"plastic": False, "harmonics": 240}),
             ("notched_strip", {"plastic": False, "harmonics": 120}),
             ("notched_cylinder", {"plastic": False, "refine": 4, "harmonics": 80}))
TINY_FORMS = (("notched_strip", {"plastic": False, "harmonics": 40, "t_end": 3.2e-5}),)


#: CPU seconds a forced form may run before it is stopped (its CPU to there and the share of the
#: steps it made are printed)
FORM_BUDGET_S = 120.0


class OverBudget(Exception):
    """A forced form's run past :data:`FORM_BUDGET_S`: (step, steps)."""


def _budget(t0: float, step: int, n_steps: int) -> None:
    if time.process_time() - t0 > FORM_BUDGET_S:
        raise OverBudget(step, n_steps)


def forms(runs) -> None:
    """Each form of the coupled solve forced in turn on elastic runs, against the prediction."""
    from smfem import coupled_solve
    from smfem.model import Model

    chooser = coupled_solve.choose
    print("| scene | settings | form | CPU s | predicted Gflop | chosen |")
    print("|---|---|---|---|---|---|")
    try:
        for name, sets in runs:
            case = get_case(name, sets)
            chosen, costs = chooser(Model(case), case.n_steps, 10**12)
            for form in ("whole", "woodbury", "krylov"):
                if form in costs and chosen in costs and costs[form].total(case.n_steps) > 20 * costs[chosen].total(case.n_steps):
                    print(f"| {name} | {' '.join(f'{k}={v}' for k, v in sets.items())} | {form} | not run: predicted "
                          f"{costs[form].total(case.n_steps) / costs[chosen].total(case.n_steps):.0f} times the chosen | | |")
                    continue
                coupled_solve.choose = lambda model, solves, nnz, form=form: (form, {})
                cpu, stopped = [], ""
                for _ in range(2):
                    t0 = time.process_time()
                    try:
                        solve(case, progress=partial(_budget, t0), with_fields=False)
                    except OverBudget as exc:
                        stopped = f" (stopped at step {exc.args[0]} of {exc.args[1]}: {exc.args[1] / exc.args[0]:.0f} times that)"
                        cpu.append(time.process_time() - t0)
                        break
                    cpu.append(time.process_time() - t0)
                flops = f"{costs[form].total(case.n_steps) / 1e9:.1f}" if form in costs else "-"
                print(f"| {name} | {' '.join(f'{k}={v}' for k, v in sets.items())} | {form} | {min(cpu):.2f}{stopped} "
                      f"| {flops} | {'yes' if form == chosen else ''} |", flush=True)
    finally:
        coupled_solve.choose = chooser


def import_seconds() -> float:
    out = subprocess.run([sys.executable, "-c", "import time; t = time.process_time(); import smfem.solver; "
                          "print(time.process_time() - t)"], capture_output=True, text=True, check=True)
    return float(out.stdout)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes", nargs="*", default=list(SCENES))
    parser.add_argument("--set", action="append", default=[], metavar="NAME:KEY=VALUE")
    parser.add_argument("--forms", action="store_true", help="the coupled solve's forms side by side, elastic runs")
    parser.add_argument("--tiny", action="store_true", help="short runs (a check that the script works)")
    args = parser.parse_args(argv)
    if args.forms:
        forms(TINY_FORMS if args.tiny else FORM_RUNS)
        return
    settings = {name: dict(SCENES[name], **(TINY[name] if args.tiny else {})) for name in args.scenes}
    for item in args.set:
        name, _, kv = item.partition(":")
        key, _, value = kv.partition("=")
        settings[name][key] = value
    print(f"imports: {import_seconds():.2f} CPU s")
    columns = ["model", "system set-up", "march", "triangular solves", "woodbury", "K x, M x", "synthesis", "law",
               "projection", "probes"]
    print("| scene | settings | dof | CPU s | " + " | ".join(columns) + " | iterations | bare solves s | CPU / bare "
          "| coupled solves s | CPU / coupled |")
    print("|" + "---|" * (len(columns) + 9))
    for name in args.scenes:
        r = profile(name, settings[name])
        print(f"| {r['scene']} | {r['settings']} | {r['n_dof']} | {r['cpu_s']:.2f} | "
              + " | ".join(f"{r[c]:.2f}" for c in columns)
              + f" | {r['iterations']} | {r['bare_solves_s']:.2f} | {r['cpu_over_bare']:.1f} | {r['coupled_solves_s']:.2f} "
              f"| {r['cpu_over_coupled']:.1f} |", flush=True)
        print(f"  ({r['solve']})", flush=True)


if __name__ == "__main__":
    main()
