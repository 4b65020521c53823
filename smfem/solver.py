"""Run a case with SMFEM: build the model, choose the system, march in time, record probes.

The solver chooses how to solve each step and names the choice in ``info['solve']``:
* elastic, homogeneous along x3: decoupled harmonics, marched in batches that fit memory, each
  harmonic factorized apart (:mod:`smfem.batched`);
* elastic, material varying along x3: a direct solve of the whole coupled block system if it
  has at most ``options.direct_max_nonzeros`` nonzeros, else the iterations below;
* elasto-plastic: the iterations (13)-(16) of additional loads with Wilkins' correction
  (:mod:`smfem.iterative`), with Anderson acceleration; the iteration matrix is the
  block-diagonal elastic system of a body homogeneous along x3, the whole coupled one where
  the material varies along x3 and it fits, else that system by conjugate gradients with the
  coupling applied matrix-free and the diagonal blocks as preconditioner (or the paper's block
  SOR, on request);
* a rigid wall: the contact layer (:mod:`smfem.contact`).

Every one of them marches with Newmark (:mod:`smfem.newmark`); an elastic run without contact
may take the 2-stage Gauss-Legendre method instead (``time_scheme=gauss``, :mod:`smfem.gauss`).
"""

from __future__ import annotations

import dataclasses
import time
from functools import partial

import numpy as np
import scipy.sparse as sp

from cases.recorder import StepRecorder
from cases.result import RunResult

from . import batched, gauss, laws, woodbury
from .contact import ContactSystem
from .exact import error_l2
from .fields import field_mesh
from .gauss import GaussSystem
from .iterative import BlockIterative
from .model import Model, ModelError
from .newmark import LinearSystem, StepFailed, march
from .options import SolverOptions
from .probes import CaseProbes
from .zones import smfem_snapshot


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
    K = (sp.block_diag([s.K for s in S], format="csr") + model.coupled_stiffness()).tocsr()
    return K, model.mass_matrix(), Q, V0, offsets


def force_terms(case, model: Model) -> list:
    """The model's timed loads (force terms, pressures with an amplitude or moving) as callables
    ``t -> Q_k(t)``, all modes stacked (:class:`smfem.newmark.Load`)."""
    return [_stacked_term(model, k, term) for k, term in enumerate(model.timed)]


def _stacked_term(model: Model, k: int, term):
    """``t -> S @ factors(t)`` (:meth:`smfem.loads.TimedLoad.factors_of`): column i of ``S`` is mode i's reduced vector in its own rows."""
    blocks = [s.Q_terms[k] for s in model.systems]
    if term.pressure is None:  # one factor for every mode
        Q = np.concatenate(blocks)
        return lambda t: float(term.factor(t)) * Q
    rows = np.concatenate([np.arange(a, b) for a, b in zip(model.offsets[:-1], model.offsets[1:])])
    cols = np.repeat(np.arange(len(blocks)), np.diff(model.offsets))
    S = sp.csr_matrix((np.concatenate(blocks), (rows, cols)), shape=(int(model.offsets[-1]), len(blocks)))
    S.eliminate_zeros()
    factors = term.factors_of(model.modes)
    return lambda t: S @ factors(t)


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
    if batched.decoupled(case, options):  # independent harmonics: marched in batches that fit memory
        return batched.solve(case, options, partial(decoupled_system, case), progress, with_fields, every, cpu0)
    model, system, how = build_system(case, options)
    return _run(case, model, system, how, progress, with_fields, cpu0, every)


def build_system(case, options: SolverOptions):
    """The model, the system that solves its steps, and the ``info['solve']`` that names it."""
    plastic = laws.get(case.material).nonlinear  # a law whose stress depends on its state: the iterations
    if case.params.get("time_scheme", "newmark") == "gauss":
        return gauss_system(case, options, plastic)
    if case.wall is not None or case.contacts:
        if plastic:
            raise ModelError(f"{case.name}: contact with plasticity is not supported: set plastic=false")
        # harmonic 0 alone for an axisymmetric scene, else every mode the wall's symmetry allows
        model = Model(case, nonlinear=not case.axisymmetric, bbar=options.bbar)
        return model, ContactSystem(model, case.dt, options, force_terms(case, model)), ContactSystem.HOW
    model = Model(case, nonlinear=plastic, bbar=options.bbar)
    coupled = bool(model.coupling)
    kind = options.iteration_matrix
    low_rank = coupled and woodbury.preferred(model)
    if kind == "auto":
        # the Woodbury form serves the iterations; an elastic run factorizes the assembled matrix
        fits = not coupled or (plastic and low_rank) or model.coupled_nonzeros() <= options.direct_max_nonzeros
        kind = "coupled" if fits else "matrix-free"
    if not plastic and (kind == "coupled" or not coupled):
        K, M, Q, _, _ = stacked(model)
        how = ("direct: the coupled block system, one factorization" if coupled
               else "decoupled harmonics, one block-diagonal factorization")
        return model, LinearSystem(K, M, Q, case.dt, force_terms(case, model)), how
    if not plastic:  # elastic but not to be factorized whole: the iterations
        model = Model(case, nonlinear=True, bbar=options.bbar)
    n = len(model.systems)
    how = {"coupled": (f"additional loads (13)-(16), the whole coupled elastic system of {n} harmonics as iteration "
                       "matrix" + (" (block-diagonal plus the cut-outs' low-rank correction, Woodbury)" if low_rank else "")
                       if coupled else f"additional loads (13)-(16), all {n} harmonics in one block-diagonal "
                       "solve per iteration (they do not couple through the stiffness)"),
           "matrix-free": f"additional loads (13)-(16), conjugate gradients on the coupled system of {n} harmonics, "
                          "the coupling applied matrix-free through the cut-outs' x3 points, the diagonal blocks as "
                          "preconditioner",
           "sor": f"block-iterative (13)-(16): block SOR over {n} harmonics, omega {options.relaxation:g}"}[kind]
    if kind != "sor" and options.anderson:
        how += f", Anderson acceleration ({options.anderson} iterates)"
    return model, BlockIterative(model, case.dt, dataclasses.replace(options, iteration_matrix=kind),
                                 force_terms(case, model)), how


def gauss_system(case, options: SolverOptions, plastic: bool):
    """:func:`build_system` for ``time_scheme=gauss``: the linear system factorized whole, or a
    :class:`ModelError` that says why not."""
    refused = ("plasticity" if plastic else "a rigid wall" if case.wall is not None else
               "contact between bodies" if case.contacts else
               f"iteration_matrix={options.iteration_matrix}" if options.iteration_matrix not in ("auto", "coupled")
               else "")
    if refused:
        raise ModelError(f"{case.name}: time_scheme=gauss takes an elastic run without contact, not {refused}: "
                         "set time_scheme=newmark")
    model = Model(case, bbar=options.bbar)
    if model.coupling and model.coupled_nonzeros() > options.direct_max_nonzeros:
        raise ModelError(f"{case.name}: time_scheme=gauss factorizes the coupled system whole, and its "
                         f"{model.coupled_nonzeros()} nonzeros exceed direct_max_nonzeros: set time_scheme=newmark")
    K, M, Q, _, _ = stacked(model)
    how = "the 2-stage Gauss-Legendre method, " + ("the coupled block system" if model.coupling else
                                                   "decoupled harmonics") + ", one complex factorization"
    return model, GaussSystem(K, M, Q, case.dt, force_terms(case, model)), how


def decoupled_system(case, model: Model) -> LinearSystem:
    """The linear system of ``model``'s decoupled harmonics, each factorized apart: Newmark's,
    or with ``time_scheme=gauss`` Gauss's (a batch of :func:`smfem.batched.solve`)."""
    K, M, Q, _, offsets = stacked(model)
    kind = GaussSystem if case.params.get("time_scheme", "newmark") == "gauss" else LinearSystem
    return kind(K, M, Q, case.dt, force_terms(case, model), blocks=offsets)


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
        steps = gauss.march if isinstance(system, GaussSystem) else march
        for state in steps(system, np.zeros_like(V0), V0, case.dt, case.n_steps):
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
