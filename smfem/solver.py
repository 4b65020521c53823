"""Run a case with SMFEM: build the model and its system (:mod:`smfem.strategy` chooses how
each step is solved and names the choice in ``info['solve']``), march in time, record probes.

Every system marches with Newmark (:mod:`smfem.newmark`); an elastic run without contact may
take the 2-stage Gauss-Legendre method instead (``time_scheme=gauss``, :mod:`smfem.gauss`).
"""

from __future__ import annotations

import time
from functools import partial

import numpy as np

from cases.recorder import StepRecorder
from cases.result import RunResult

from . import batched, gauss
from .exact import error_l2
from .fields import field_mesh
from .newmark import StepFailed
from .options import SolverOptions
from .strategy import Batched, Run, choose
from .probes import CaseProbes
from .zones import smfem_snapshot


def solve(case, options: SolverOptions | None = None, progress=None, with_fields: bool = True,
          every: int = 0) -> RunResult:
    """Transient SMFEM run of a case.

    Parameters
    ----------
    case : cases.Case
    options : how to solve (:class:`smfem.options.SolverOptions`; default: the measured choices)
    progress : optional callable ``(step, n_steps)``
    with_fields : also synthesize the 3-D field at the last computed step
    every : also the field every ``every`` steps, t = 0 included (``result.frames``; 0: none)
    """
    cpu0 = time.process_time()
    options = options or SolverOptions()
    run = Run(case, options)  # one: its conditions build the model that its strategy then takes
    strategy = choose(run)
    if strategy is Batched:  # independent harmonics: marched in batches that fit memory
        return batched.solve(case, options, partial(Batched.system, case), progress, with_fields, every, cpu0)
    model, system, how = strategy.build(run)
    return _run(case, model, system, how, progress, with_fields, cpu0, every)


def _field(model, system, state):
    """The synthesized 3-D field of a state: displacement, velocity, stress, plastic strain."""
    split = lambda x: np.split(x, model.offsets[1:-1])
    if not hasattr(system, "peps"):
        return field_mesh(model, split(state.u), v_modes=split(state.v))
    return field_mesh(model, split(state.u), peps=system.peps, peps_x3=system.peps_x3, v_modes=split(state.v),
                      relaxed=system.relaxed)


def _run(case, model, system, how, progress, with_fields, cpu0, every=0) -> RunResult:
    """March ``system`` over the case's window, recording every probe after every step; a
    failed step ends the run with what came before it."""
    probes = CaseProbes(case, model, system)
    state = None  # the frame and snapshot below read the state being recorded
    plastic = case.material.plastic and hasattr(system, "peps")
    snapshot = (lambda t: smfem_snapshot(t, model, case, system.peps, system.peps_x3)) if plastic else None
    recorder = StepRecorder(case, probes.names, every, progress, frame=lambda: _field(model, system, state),
                            snapshot=snapshot)
    V0 = np.concatenate([s.V0 for s in model.systems])
    try:
        for state in gauss.march_for(system)(system, np.zeros_like(V0), V0, case.dt, case.n_steps):
            row = probes.values(state, system)
            system.observe(state)
            recorder.record(state.n, row, state.iterations)
    except StepFailed as exc:
        recorder.fail(str(exc))
    verdict, facts = system.report()
    recorder.fail(verdict)
    its = np.array(recorder.iterations or [0])
    info = {"harmonics_used": model.harmonics_used(), "factorizations": system.factorizations,
            "n_elements": model.mesh.n_elements, "solve": how,
            "iterations_mean": float(its.mean()), "iterations_max": int(its.max()), **facts}
    mesh = _field(model, system, state) if with_fields else None
    cpu = time.process_time() - cpu0
    if case.exact is not None and state is not None:  # a measurement, not part of the solve's CPU
        info["error_l2"] = error_l2(model, np.split(state.u, model.offsets[1:-1]), case.exact, state.n * case.dt)
    return recorder.result(n_dof=model.n_dof, cpu_time_s=cpu, mesh=mesh, info=info)
