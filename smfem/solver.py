"""Run a case with SMFEM: build the model, step in time, record probes.

The solver chooses how to solve each step and names the choice in ``info['solve']``:
* elastic, homogeneous along x3: decoupled harmonics, one block-diagonal factorization;
* elastic, material varying along x3: a direct solve of the whole coupled block system if it
  has at most ``DIRECT_MAX_NONZEROS`` nonzeros, else the block-iterative algorithm;
* elasto-plastic: the iterations (13)-(16) of additional loads with Wilkins' correction; the
  iteration matrix is the whole coupled elastic system where the material varies along x3 and
  it fits (block SOR converges slowly when cut-outs couple the harmonics strongly), else the
  paper's block SOR over the harmonics with the diagonal blocks factorized once.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from cases.result import RunResult

from .fields import field_mesh
from .iterative import BlockIterative, NotConverged
from .model import Model, ModelError
from .newmark import LinearNewmark
from .probes import PlasticStrainProbes, ProbeSet
from .zones import smfem_snapshot

#: the largest coupled system factorized directly (nonzeros of K + a0 M)
DIRECT_MAX_NONZEROS = 40_000_000
#: relaxation of the block SOR (see the omega study in benchmarks/)
OMEGA = 1.0
#: iterations allowed per step before a run stops as not converged
MAX_ITERATIONS = 200


def stacked(model: Model):
    """``K``, ``M``, ``Q``, ``V0`` of all modes stacked, and the offsets of each mode.

    Decoupled modes give a block-diagonal ``K`` and a mass diagonal; coupled ones (material
    varying along x3) the whole block system with the mass as a sparse matrix.
    """
    S = model.systems
    offsets = np.cumsum([0] + [s.K.shape[0] for s in S])
    Q, V0 = np.concatenate([s.Q for s in S]), np.concatenate([s.V0 for s in S])
    if not model.coupling:
        return sp.block_diag([s.K for s in S], format="csr"), model.mass_matrix(), Q, V0, offsets
    model.assemble_coupled_stiffness()  # a missing block must never count as zero
    n = len(S)
    Kb = [[model.coupling[i, j][0] if (i, j) in model.coupling else None for j in range(n)] for i in range(n)]
    for i, s in enumerate(S):
        Kb[i][i] = s.K
    return sp.bmat(Kb, format="csr"), model.mass_matrix(), Q, V0, offsets


def solve(case, progress=None, with_fields: bool = True, direct: bool | None = None) -> RunResult:
    """Transient SMFEM run of a case.

    Parameters
    ----------
    case : cases.Case
    progress : optional callable ``(step, n_steps)``
    with_fields : also synthesize the 3-D field at the last computed step
    direct : force (True) or forbid (False) the direct coupled solve of an elastic
        inhomogeneous case; None lets the solver choose by size
    """
    cpu0 = time.process_time()
    plastic = case.material.plastic
    if case.wall is not None:
        if plastic:
            raise ModelError(f"{case.name}: contact with plasticity is not supported: set plastic=false")
        from .contact_run import contact_model, solve_contact

        return solve_contact(case, contact_model(case), progress, with_fields, cpu0)
    model = Model(case, nonlinear=plastic)
    coupled = bool(model.coupling)
    use_direct = coupled and (model.coupled_nonzeros() <= DIRECT_MAX_NONZEROS if direct is None else direct)
    if use_direct:
        model.assemble_coupled_stiffness()
    if not plastic and (use_direct or not coupled):
        return _linear(case, model, progress, with_fields, cpu0)
    if not plastic:  # elastic but too large to factorize whole: the iterative path
        model = Model(case, nonlinear=True)
    return _iterative(case, model, progress, with_fields, cpu0, use_direct)


def _history(case, linear_names, linear_values, plastic_names=(), plastic_values=None):
    columns = dict(zip(linear_names, linear_values.T))
    if plastic_values is not None:
        columns.update(zip(plastic_names, plastic_values.T))
    return {name: columns[name] for name in case.probe_names}


def _linear(case, model, progress, with_fields, cpu0) -> RunResult:
    probes = ProbeSet(model, case.probes)
    K, M, Q, V0, offsets = stacked(model)
    stepper = LinearNewmark(K, M, Q, case.dt)
    n = case.n_steps
    values = np.empty((n + 1, len(probes.names)))
    state = stepper.initial(np.zeros_like(Q), V0)
    values[0] = probes.evaluate(state.u, state.v)
    for state in stepper.run(state, n):
        values[state.n] = probes.evaluate(state.u, state.v)
        if progress:
            progress(state.n, n)
    mesh = field_mesh(model, np.split(state.u, offsets[1:-1])) if with_fields else None
    return RunResult(
        t=np.arange(n + 1) * case.dt, history=_history(case, probes.names, values), n_dof=model.n_dof,
        iterations=[1] * n, cpu_time_s=time.process_time() - cpu0, mesh=mesh,
        info={"harmonics_used": model.harmonics_used(), "factorizations": stepper.factorizations,
              "n_elements": model.mesh.n_elements,
              "solve": "direct: the coupled block system, one factorization" if model.coupling
              else "decoupled harmonics, one block-diagonal factorization"},
    )


def _iterative(case, model, progress, with_fields, cpu0, direct: bool) -> RunResult:
    linear = [p for p in case.probes if p.field != "peps"]
    plastic = [p for p in case.probes if p.field == "peps"]
    probes, pprobes = ProbeSet(model, linear), PlasticStrainProbes(model, plastic)
    coupled = stacked(model)[:2] if direct else None
    solver = BlockIterative(model, case.dt, omega=OMEGA, tol=case.params["tol"], max_iter=MAX_ITERATIONS,
                            coupled=coupled)
    n = case.n_steps
    values, pvalues = np.empty((n + 1, len(linear))), np.empty((n + 1, len(plastic)))
    zero = [np.zeros_like(s.Q) for s in model.systems]
    u, v, a = solver.initial(zero, [s.V0 for s in model.systems])

    def record(k):
        values[k] = probes.evaluate(np.concatenate(u), np.concatenate(v))
        pvalues[k] = pprobes.evaluate(solver.state.peps)

    record(0)
    snapshot_steps = {int(round(t / case.dt)): t for t in case.references.get("plastic_zone_times", ())}
    snapshots = []
    iterations, message = [], ""
    for k in range(1, n + 1):
        try:
            u, v, a, its = solver.step(u, v, a, k, k * case.dt)
        except NotConverged as exc:
            message = str(exc)
            break
        iterations.append(its)
        record(k)
        if k in snapshot_steps and case.material.plastic:
            snapshots.append(smfem_snapshot(k * case.dt, model, case, solver.state.peps))
        if progress:
            progress(k, n)
    done = len(iterations) + 1
    mesh = field_mesh(model, u, peps=solver.state.peps) if with_fields else None
    its = np.array(iterations or [0])
    return RunResult(
        t=np.arange(done) * case.dt,
        history={k: h[:done] for k, h in _history(case, probes.names, values, pprobes.names, pvalues).items()},
        n_dof=model.n_dof, iterations=iterations, converged=not message, message=message,
        cpu_time_s=time.process_time() - cpu0, mesh=mesh,
        info={"harmonics_used": model.harmonics_used(), "factorizations": solver.factorizations,
              "n_elements": model.mesh.n_elements, "n_x3_points": len(model.x3),
              "solve": "iterative (13)-(16) with the whole coupled elastic system as iteration matrix" if direct
              else f"block-iterative (13)-(16): block SOR over {len(model.systems)} harmonics, omega {OMEGA:g}",
              "iterations_mean": float(its.mean()), "iterations_max": int(its.max()),
              "time_breakdown_s": dict(solver.timings)},
        snapshots=snapshots,
    )
