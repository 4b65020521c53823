"""Harmonics that do not couple, marched in batches that fit memory.

A linear run of a body homogeneous along x3, without contact, has independent harmonics: its
step matrix is block-diagonal (one block per harmonic), and every probe and the synthesized
field are sums over the harmonics (12). So a batch of harmonics marches through the whole
window alone, adds its share to every probe row, leaves its amplitudes at the last step (and at
the frames' steps) for the field, and frees its stiffness and factors before the next batch
starts. What a run holds is the model without its stiffness (the modes' maps, masses and
loads), one batch's stiffness and factors, and the probe rows: the factors, by far the largest,
no longer grow with the harmonics. Each harmonic of a batch is factorized apart
(:class:`smfem.linalg.BlockFactors`), which needs no copy of the batch's whole matrix.

A batch's memory is predicted before it is built: one harmonic, the one with the most
unknowns, is factorized as the run's systems are, and its factors' and stiffness's bytes,
scaled by each harmonic's unknowns, are that harmonic's share (:func:`shares`). Batches take
the harmonics in order while the sum of their shares stays within the budget: the option
``batch_memory_mb``, and never more than half the memory the machine has available (Linux's
``MemAvailable`` in /proc/meminfo, else the free pages ``os.sysconf`` reports), the other half
left to the rest of the run, the processes beside it and the prediction's error. A batch takes
one harmonic at least. Small batches cost nothing but a few bookkeeping operations per step
and batch (the march, the loads, the probes), every step of a batch being a solve per harmonic
as in one batch of all: so the option's default is small, a few harmonics of a coarse section
or one of a fine one, and large harmonics march one by one (benchmarks/README.md measures
the batch sizes).

The probe rows, the field and the error come out as those of one batch of all harmonics, to
round-off; the progress callback sees the whole run as ``n_steps`` steps (each batch its share
of them, by its unknowns).
"""

from __future__ import annotations

import time

import numpy as np

from cases.recorder import StepRecorder
from cases.result import RunResult

from . import gauss, inhomogeneity, laws
from .exact import error_l2
from .fields import field_mesh
from .linalg import available_bytes
from .model import Model
from .options import SolverOptions
from .probes import CaseProbes

MB = 2**20
#: vectors of a harmonic's unknowns a batch holds while it marches (the states' u, v, a, the
#: predictor, the loads and the right-hand sides; complex ones twice), in 8-byte entries
STEP_VECTORS = 16


def decoupled(case, options: SolverOptions) -> bool:
    """Whether the run's harmonics are independent: an elastic law, no wall and no contact, the
    material the same all along x3, and no iterations asked for (under Gauss another
    ``iteration_matrix`` is refused by :func:`smfem.strategy.build_system`)."""
    return (not laws.get(case.material).nonlinear and case.wall is None and not case.contacts
            and not inhomogeneity.varies(case) and options.iteration_matrix in ("auto", "coupled"))


def shares(model: Model, make_system) -> np.ndarray:
    """Each harmonic's predicted memory in a batch, bytes (n_modes,): the factors and
    stiffness of the harmonic with the most unknowns, built by ``make_system`` (see
    :func:`solve`) and measured, times the square of each harmonic's unknowns over its, plus
    the harmonic's step vectors. On one section the harmonics differ in their unknowns per
    node (a ring's axisymmetric ones have two or one of three), and a block's nonzeros, in
    its stiffness and its factors alike, grow as the square of those."""
    unknowns = np.diff(model.offsets)
    largest = int(np.argmax(unknowns))
    system = make_system(model.restricted([largest]))
    K = system.K
    held = system.lu.nbytes + K.data.nbytes + K.indices.nbytes + K.indptr.nbytes
    return held * (unknowns / unknowns[largest]) ** 2 + 8 * STEP_VECTORS * unknowns


def batches(share: np.ndarray, budget: float) -> list[range]:
    """Consecutive harmonics whose shares sum to at most ``budget`` (one at least in each)."""
    out, start, total = [], 0, 0.0
    for i, s in enumerate(share):
        if i > start and total + s > budget:
            out.append(range(start, i))
            start, total = i, 0.0
        total += s
    out.append(range(start, len(share)))
    return out


def solve(case, options: SolverOptions, make_system, progress=None, with_fields: bool = True, every: int = 0,
          cpu0: float | None = None) -> RunResult:
    """A decoupled linear run (:func:`decoupled`) marched in batches of harmonics.

    Parameters
    ----------
    case : cases.Case
    options : :class:`smfem.options.SolverOptions` (``bbar``, ``batch_memory_mb``)
    make_system : ``make_system(model)`` -> the linear system (:class:`smfem.newmark.LinearSystem`
        or :class:`smfem.gauss.GaussSystem`) of a model of some of the harmonics, each factorized
        apart (its ``blocks``, :meth:`smfem.strategy.Batched.system`)
    progress, with_fields, every : as :func:`smfem.solver.solve`
    cpu0 : the process time the run started at (default: now)
    """
    cpu0 = time.process_time() if cpu0 is None else cpu0
    model = Model(case, bbar=options.bbar, stiffness=False)
    share = shares(model, make_system)
    budget = min(options.batch_memory_mb * MB, available_bytes() / 2)
    groups = batches(share, budget)
    sums = Sums(case, model, every)
    for group in groups:
        sums.add(case, model, group, make_system(model.restricted(group)), progress)
    split = lambda x: np.split(x, model.offsets[1:-1])
    field = lambda u, v: field_mesh(model, split(u), v_modes=split(v))
    recorder = StepRecorder(case, case.probe_names, every, frame=lambda: field(*sums.frames[step]))
    for step in range(case.n_steps + 1):
        recorder.record(step, sums.rows[step], sums.iterations[step])
    largest = max(share[g].sum() for g in groups) / MB
    count = lambda n, one, many: f"{n} {one if n == 1 else many}"
    how = (f"{sums.scheme}decoupled harmonics, each factorized apart, marched in "
           f"{count(len(groups), 'batch', 'batches')} of at most {count(max(map(len, groups)), 'harmonic', 'harmonics')} "
           f"(the largest batch predicted at {largest:.3g} MB, the budget {budget / MB:.3g} MB)")
    info = {"harmonics_used": model.harmonics_used(), "factorizations": len(model.systems) + 1,
            "n_elements": model.mesh.n_elements, "solve": how, "iterations_mean": float(sums.iterations[1:].mean()),
            "iterations_max": int(sums.iterations.max()), "batches": [len(g) for g in groups],
            "batch_memory_mb": round(largest, 1), "memory_budget_mb": round(budget / MB, 1)}
    mesh = field(*sums.last) if with_fields else None
    cpu = time.process_time() - cpu0
    if case.exact is not None:  # a measurement, not part of the solve's CPU
        info["error_l2"] = error_l2(model, split(sums.last[0]), case.exact, case.n_steps * case.dt)
    return recorder.result(n_dof=model.n_dof, cpu_time_s=cpu, mesh=mesh, info=info)


class Sums:
    """What the batches add up to: every probe's row at every step (n_steps + 1, n_probes), the
    iterations of each step, and the amplitudes of all harmonics (each batch fills its own rows)
    at the last step (``last``: u, v) and at the frames' steps (``frames``: step -> (u, v))."""

    def __init__(self, case, model: Model, every: int):
        self.rows = np.zeros((case.n_steps + 1, len(case.probe_names)))
        self.iterations = np.zeros(case.n_steps + 1, int)
        self.last = np.zeros(model.n_dof), np.zeros(model.n_dof)
        self.frames = {n: (np.zeros(model.n_dof), np.zeros(model.n_dof))
                       for n in (range(0, case.n_steps + 1, every) if every else ())}
        self.scheme = ""  # "the 2-stage Gauss-Legendre method, " once a Gauss system marched
        self.reported = 0

    def add(self, case, model: Model, group: range, system, progress) -> None:
        """March ``system``, the harmonics ``group``'s, through the window and add its share;
        ``progress(step, n_steps)`` counts the batches before it and its own steps by their
        unknowns."""
        part = model.restricted(group, stiffness=False)  # the probes' view: no stiffness of its own
        probes = CaseProbes(case, part, system)
        n_steps, offsets = case.n_steps, model.offsets
        rows = slice(offsets[group.start], offsets[group.stop])
        done, weight = offsets[group.start] / model.n_dof, (offsets[group.stop] - offsets[group.start]) / model.n_dof
        V0 = np.concatenate([s.V0 for s in part.systems])
        self.scheme = "the 2-stage Gauss-Legendre method, " if isinstance(system, gauss.GaussSystem) else ""
        for state in gauss.march_for(system)(system, np.zeros_like(V0), V0, case.dt, n_steps):
            self.rows[state.n] += probes.values(state, system)
            self.iterations[state.n] = max(self.iterations[state.n], state.iterations)
            if state.n in self.frames:
                self.frames[state.n][0][rows], self.frames[state.n][1][rows] = state.u, state.v
            now = int((done + weight * state.n / n_steps) * n_steps)
            if progress is not None and now > self.reported:
                progress(now, n_steps)
                self.reported = now
        self.last[0][rows], self.last[1][rows] = state.u, state.v
