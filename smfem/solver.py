"""Run a case with SMFEM: build the model, step in time, record probes."""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from .fields import field_mesh
from .model import Model, ModelError
from .newmark import LinearNewmark
from .probes import ProbeSet
from .result import RunResult


def stacked(model: Model):
    """``K``, ``M``, ``Q``, ``V0`` of all modes stacked, and the offsets of each mode.

    Decoupled modes give a block-diagonal ``K`` and a mass diagonal; coupled ones (material
    varying along x3) the whole block system with the mass as a sparse matrix.
    """
    S = model.systems
    offsets = np.cumsum([0] + [s.K.shape[0] for s in S])
    Q, V0 = np.concatenate([s.Q for s in S]), np.concatenate([s.V0 for s in S])
    if not model.coupling:
        return sp.block_diag([s.K for s in S], format="csr"), np.concatenate([s.M for s in S]), Q, V0, offsets
    n = len(S)
    Kb = [[model.coupling[i, j][0] if (i, j) in model.coupling else None for j in range(n)] for i in range(n)]
    Mb = [[model.coupling[i, j][1] if (i, j) in model.coupling else None for j in range(n)] for i in range(n)]
    for i, s in enumerate(S):
        Kb[i][i], Mb[i][i] = s.K, sp.diags(s.M)
    return sp.bmat(Kb, format="csr"), sp.bmat(Mb, format="csr"), Q, V0, offsets


def solve(case, progress=None, with_fields: bool = True) -> RunResult:
    """Linear elastic dynamics of a case homogeneous along x3.

    Parameters
    ----------
    case : cases.Case
    progress : optional callable ``(step, n_steps)``
    with_fields : also synthesize the 3-D field at the final time
    """
    if case.material.plastic:
        raise ModelError(f"{case.name}: the elasto-plastic solver is not part of this version; use --set plastic=false")
    if case.wall is not None:
        raise ModelError(f"{case.name}: contact is not part of this version")
    cpu0 = time.process_time()
    model = Model(case)
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
    cpu = time.process_time() - cpu0
    return RunResult(
        t=np.arange(n + 1) * case.dt,
        history=dict(zip(probes.names, values.T)),
        n_dof=model.n_dof,
        iterations=[1] * n,
        cpu_time_s=cpu,
        mesh=mesh,
        info={"harmonics_used": model.harmonics_used(), "factorizations": stepper.factorizations,
              "n_elements": model.mesh.n_elements,
              "solve": "direct: the coupled block system, one factorization" if model.coupling
              else "decoupled harmonics, one block-diagonal factorization"},
    )
