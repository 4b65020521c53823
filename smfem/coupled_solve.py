"""Solvers of the stacked elastic ``A = K + a0 M`` of all modes, and the choice among them.

The elastic path (one solve per step) and the plastic one (a solve per iteration) use the same:

* :class:`BlockDiagonal`: harmonics that do not couple, one factorization of the diagonal blocks;
* :class:`Whole`: the assembled coupled matrix factorized. Its cut-out dofs of every mode are
  linked to each other, so their Schur complement is dense: ``n_c = modes x cut-out dofs``
  unknowns, about ``n_c^3 / 3`` flops and ``n_c^2 / 2`` entries of fill (the notched strip at 400
  harmonics: ``n_c`` 4800, 10.4M entries measured, 11.5M predicted);
* :class:`smfem.woodbury.CutoutWoodbury`: the diagonal blocks of the body without its cut-outs
  plus a dense capacitance of the cut-outs' rank ``r = q 2 c`` (``q`` x3 point combinations
  times twice the ``c`` cut-out dofs, however many harmonics): ``r^3`` flops (its Cholesky
  factor and inverse), the kernel over the pairs of points as the capacitance is formed
  (``q (q + 1) / 2 (2 c)^2`` modes and ``q (q + 1) (2 c)^3``), solves with the blocks for the
  ``c`` cut-out dofs, and per solve two block solves and ``2 r^2``;
* :class:`Krylov`: conjugate gradients on the exact coupled operator
  (:class:`smfem.coupling.StackedOperator`) preconditioned by the diagonal blocks, each solve
  started from the last one's answer; no set-up beyond the blocks, but iterations per solve
  that no count predicts (``iteration_matrix=matrix-free``, and where neither direct form fits
  in memory).

:func:`choose` takes the direct form of least predicted cost, set-up plus the run's solves, that
fits in memory (benchmarks/coupled_profile.py measures the prediction against the runs).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from . import woodbury
from .coupling import StackedOperator
from .linalg import BlockFactors, available_bytes, factorize_spd, stacked_step, step_blocks

#: the share of the memory available at the start that a factorization may take
MEMORY_SHARE = 0.6


class BlockDiagonal:
    """``A`` of modes that do not couple: its diagonal blocks, one factorization."""

    name = "block-diagonal"

    def __init__(self, model, a0: float):
        self.lu = factorize_spd(stacked_step(((s.K, s.M) for s in model.systems), a0))

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self.lu.solve(b)


class Whole:
    """The assembled coupled ``A``, one sparse factorization."""

    name = "whole"

    def __init__(self, model, a0: float):
        blocks = stacked_step(((s.K, s.M) for s in model.systems), a0)
        self.lu = factorize_spd(blocks + model.coupled_stiffness() + a0 * model.coupled_mass)

    def solve(self, b: np.ndarray) -> np.ndarray:
        return self.lu.solve(b)


class Woodbury(woodbury.CutoutWoodbury):
    name = "woodbury"


class Krylov:
    """``A x = b`` by preconditioned conjugate gradients to a relative residual ``rtol``,
    started from the last solve's ``x`` (a step's answer is close to the last one's)."""

    name = "krylov"

    def __init__(self, model, a0: float, rtol: float, maxiter: int, op: StackedOperator | None = None):
        op = op or StackedOperator(model)
        n = model.n_dof
        self.diagonal = BlockFactors(step_blocks(((s.K, s.M) for s in model.systems), a0))
        self.A = sla.LinearOperator((n, n), matvec=lambda v: op.K(v) + a0 * op.M(v), dtype=float)
        self.blocks = sla.LinearOperator((n, n), matvec=self.diagonal.solve, dtype=float)
        self.rtol, self.maxiter, self.iterations, self.last = rtol, maxiter, 0, np.zeros(n)

    def solve(self, b: np.ndarray, start: np.ndarray | None = None) -> np.ndarray:
        count = []
        x, _ = sla.cg(self.A, b, x0=self.last if start is None else start, rtol=self.rtol, M=self.blocks,
                      maxiter=self.maxiter, callback=count.append)
        self.iterations += len(count)
        self.last = x
        return x


@dataclass(frozen=True)
class Cost:
    """Predicted flops of set-up and of one solve, and bytes of the factors."""

    setup: float
    per_solve: float
    memory: float

    def total(self, solves: int) -> float:
        return self.setup + solves * self.per_solve


def predicted_costs(model) -> dict[str, Cost]:
    """The direct forms' predicted costs (the module's docstring): ``{'whole', 'woodbury'}``."""
    modes = len(model.systems)
    cut = len(woodbury.cutout_dofs(model))
    n_c = modes * cut
    n_points = woodbury.point_combinations(model)[1].shape[1]
    rank = n_points * 2 * cut
    # a block solve: forward and back through factors of about twice the blocks' nonzeros
    block = 4.0 * sum(s.K.nnz for s in model.systems)
    whole = Cost(setup=n_c**3 / 3, per_solve=block + 2.0 * n_c**2, memory=8.0 * (n_c**2 / 2 + block / 2))
    # the capacitance as CutoutWoodbury._capacitance forms it: the kernel over the pairs of
    # points, one product over the modes per pair of basis types, then F' K F per pair (the
    # notched strip at 120 harmonics: 0.97e9 flops, where rank^2 n_c took it as 2.25e9 and chose
    # the whole factorization, 15-25 % dearer on the run)
    kernel = n_points * (n_points + 1) / 2 * (2 * cut) ** 2 * modes + n_points * (n_points + 1) * (2 * cut) ** 3
    low_rank = Cost(setup=cut * block + kernel + rank**3,
                    per_solve=2 * block + 2.0 * rank**2 + 4.0 * modes * n_points * cut,
                    memory=8.0 * (rank * n_c + rank**2 + block))
    return {"whole": whole, "woodbury": low_rank}


def choose(model, solves: int, max_nonzeros: int, memory: float | None = None) -> tuple[str, dict[str, Cost]]:
    """The form to solve ``model``'s coupled ``A`` with over ``solves`` solves: ``'block-diagonal'``
    where the modes do not couple, else the direct form of least predicted cost that fits in
    ``MEMORY_SHARE`` of ``memory`` (the whole one also within ``max_nonzeros`` coupled
    nonzeros), else ``'krylov'``; and the predicted costs."""
    if not model.coupling:
        return BlockDiagonal.name, {}
    costs = predicted_costs(model)
    budget = MEMORY_SHARE * (available_bytes() if memory is None else memory)
    fits = {name: c for name, c in costs.items() if c.memory <= budget
            and (name != "whole" or model.coupled_nonzeros() <= max_nonzeros)}
    if not fits:
        return Krylov.name, costs
    return min(fits, key=lambda name: fits[name].total(solves)), costs


def build(name: str, model, a0: float, krylov_rtol: float = 1e-10, krylov_maxiter: int = 1000, op=None):
    """The solver ``name`` (of :func:`choose`) of ``model``'s ``K + a0 M``."""
    if name == Krylov.name:
        return Krylov(model, a0, krylov_rtol, krylov_maxiter, op)
    return {BlockDiagonal.name: BlockDiagonal, Whole.name: Whole, Woodbury.name: Woodbury}[name](model, a0)
