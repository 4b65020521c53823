"""The reference solver's linear algebra: its one sparse factorization (SuperLU) and the
tangents of Newton solved on it (:class:`PreconditionedTangent`)."""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg as sla


#: SuperLU takes the diagonal pivot unless it is this much smaller than the column's largest:
#: 0, always. The matrices are symmetric positive definite (K + a0 M, the tangent of
#: associative plasticity plus a0 M) or singular (a static collapse, reported as such), and an
#: off-diagonal pivot undoes the ordering: with thresholds 1 and 0.01 the property test of
#: tests/test_bad_input.py (E = 1e15, tau_s = 1: a nearly singular tangent) drove one
#: factorization past 24 GB.
DIAGONAL_PIVOT = 0.0


def factorize(A) -> sla.SuperLU:
    """LU factors of the square sparse matrix ``A`` (scipy SuperLU).

    The minimum-degree ordering on the structure of ``A' + A`` suits the structurally symmetric
    finite element matrices here: on the 2D notched cylinder (6.4k and 25k dofs) it fills 3.3
    and 3.1 times less than SuperLU's default COLAMD and factorizes 3.6 and 3.8 times faster.
    """
    return sla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=DIAGONAL_PIVOT,
                    options={"SymmetricMode": True})


#: the consistent mass solved by conjugate gradients stops at this residual relative to the
#: right-hand side's: round-off (its solution equals the factorized mass's to about 1e-14)
MASS_RTOL = 1e-14
#: CG iterations on the mass before it is factorized after all (Jacobi-preconditioned, the
#: consistent mass of these elements takes 30-40)
MASS_MAX_ITERATIONS = 500


def solve_mass(M, b: np.ndarray) -> np.ndarray:
    """``M x = b`` for a consistent mass ``M`` (positive definite, its condition bounded on any
    mesh): conjugate gradients preconditioned by its diagonal, which leave no factors in
    memory and cost a fraction of a factorization in 3D; the factors if CG stops short."""
    x, info = sla.cg(M, b, rtol=MASS_RTOL, atol=0.0, maxiter=MASS_MAX_ITERATIONS,
                     M=sla.LinearOperator(M.shape, matvec=lambda r, d=M.diagonal(): r / d, dtype=float))
    return x if info == 0 and np.isfinite(x).all() else factorize(M).solve(b)


#: how a Newton tangent ``K_t + c M`` is solved (the reference FEM's option ``linear_solver``):
#: ``superlu`` factorizes each tangent; ``pcg`` runs conjugate gradients on it, preconditioned
#: by the factors of the elastic ``K + c M`` that every step already has (the tangent differs
#: from it only at the yielding points, so few iterations do); ``auto`` is ``pcg`` where the
#: tangent is symmetric, else ``superlu``
AUTO, SUPERLU, PCG = "auto", "superlu", "pcg"
LINEAR_SOLVERS = (AUTO, SUPERLU, PCG)
#: CG stops at this residual relative to the right-hand side's: far below Newton's tolerance
#: on the step (the histories equal the factorized tangent's to 5e-13 on the notched scenes)
PCG_RTOL = 1e-10
#: CG iterations before the tangent is factorized after all (a tangent near singular: collapse).
#: A factorization costs 18-53 CG iterations (2D and 3D, benchmarks/README.md), so past 100 CG
#: is the dearer path; the notched scenes' tangents take 7-51 on average and none reaches 100 at
#: r1 (the reference's quasi-static collapse test: 8.4 -> 5.1 s against 300)
PCG_MAX_ITERATIONS = 100


class PreconditionedTangent:
    """``(A + By' W By) x = r`` by preconditioned conjugate gradients: ``A = K + c M`` through
    its factors ``lu`` (the preconditioner) and its product; the yielding points' correction
    ``By' W By`` applied point by point (``W``: ``(n_y, nc, nc)`` blocks of the tangent minus the
    elastic matrix, times the points' weights), never assembled. ``fallback()`` returns the
    factorized tangent, used when CG does not converge.

    Attributes
    ----------
    iterations : CG iterations over all solves with this tangent
    """

    def __init__(self, A, lu, By, blocks: np.ndarray, fallback):
        self.A, self.lu, self.By, self.blocks = A, lu, By, blocks
        self._fallback, self._factors = fallback, None
        self.iterations = 0

    def matvec(self, x: np.ndarray) -> np.ndarray:
        e = (self.By @ x).reshape(self.blocks.shape[0], -1)
        return self.A @ x + self.By.T @ np.einsum("qij,qj->qi", self.blocks, e).ravel()

    def solve(self, r: np.ndarray) -> np.ndarray:
        if self._factors is not None:
            return self._factors.solve(r)
        n = r.shape[0]
        count = [0]

        def step(_):
            count[0] += 1

        x, info = sla.cg(sla.LinearOperator((n, n), matvec=self.matvec, dtype=float), r, rtol=PCG_RTOL,
                         atol=0.0, maxiter=PCG_MAX_ITERATIONS,
                         M=sla.LinearOperator((n, n), matvec=self.lu.solve, dtype=float), callback=step)
        self.iterations += count[0]
        if info != 0 or not np.isfinite(x).all():
            self._factors = self._fallback()
            return self._factors.solve(r)
        return x

    @property
    def factorized(self) -> bool:
        """Whether CG gave up and the tangent was factorized."""
        return self._factors is not None
