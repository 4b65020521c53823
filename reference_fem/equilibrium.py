"""Equilibrium ``f_int(u) + c M u = rhs`` on the free dofs: elastic and elasto-plastic.

``c = a0`` (Newmark) gives one time step, ``c = 0`` a static load step. The effective matrix
``K + c M`` is factorized once (scipy ``splu``); elastic steps only back-substitute. The
elasto-plastic Newton iteration starts with that elastic factorization (exact when no point
yields); while points are yielding it solves the consistent tangent by conjugate gradients
preconditioned with those same factors (``linear_solver='pcg'``, the default where the tangent
is symmetric: no factorization in the step) or factorizes it (``'superlu'``). Measured in 3D
(one thread): the notched cylinder r1 9.0 against 20.3 CPU s, r2 50.5 against 125 s; the
notched strip r1 19.7 against 27.4 s (16 CG iterations per Newton iteration there, ideal
plasticity softening the tangent most), r2 129 against 155 s. Histories equal to 5e-13.
"""

from __future__ import annotations

import functools

import numpy as np

from . import forms
from .linalg import AUTO, LINEAR_SOLVERS, SUPERLU, PreconditionedTangent, factorize

#: Newton iterations allowed per step before the run stops as not converged
MAX_ITERATIONS = 50
#: full Newton steps before a step that does not lower the residual is halved (ideal
#: plasticity near collapse can make Newton cycle: the notched strip at refine 2, step 88)
LINE_SEARCH_AFTER = 10
#: halvings of one Newton step at most
LINE_SEARCH_HALVINGS = 6
#: a residual this many times the step's first one means Newton diverges: stop at once
DIVERGENCE = 1e6


class NotConverged(RuntimeError):
    """Newton did not reach the tolerance within :data:`MAX_ITERATIONS`."""


class Elastic:
    """Linear system ``(K + c M) u = rhs`` restricted to ``model.free``.

    Attributes
    ----------
    K, M : stiffness and mass on the free dofs (csr); ``B``: the strain operator on them
        (:attr:`~reference_fem.model.Model.free_B`, made when first read)
    factorizations : int, number of ``splu`` calls on ``K + c M`` or a tangent (1 here)
    sigma : (n_qp, nc) stress of the last solution (Pa), Mandel, mesh frame
    state : the material law's committed state (:mod:`reference_fem.laws`)
    peps : (n_qp,) equivalent plastic strain (zero for an elastic body)
    """

    def __init__(self, model, c: float):
        self.model = model
        self.c = c
        free = model.free
        self.M = model.M[free][:, free]
        self.K = model.stiffness()[free][:, free]
        self.A = (self.K + c * self.M).tocsc()
        self.factorizations = 1
        nc = forms.n_components(model.dim)
        self.sigma = np.zeros((model.n_qp, nc))
        self._u = None  # the solution whose stress is not computed yet (see ``sigma``)
        self.law = model.law
        self.state = self.law.initial_state(model.n_qp)

    @property
    def B(self):
        return self.model.free_B

    @functools.cached_property
    def lu(self):
        """The factors of ``A``, made when first asked for: after the time march has solved
        ``M a0 = Q`` (:func:`.linalg.solve_mass`, whose factors, where CG stops short, are freed
        by then): a large 3D run's peak memory holds one set of factors, not both."""
        return factorize(self.A)

    @property
    def peps(self) -> np.ndarray:
        return self.law.equivalent_plastic_strain(self.state)

    @property
    def sigma(self) -> np.ndarray:
        """The stress of the last solution at every quadrature point, ``(n_qp, nc)``: an elastic
        step computes it only when asked (a step's probes read a few points, :meth:`stress_at`;
        the product over all points cost a third of a 3D step's back-substitution)."""
        if self._sigma is None:
            self._sigma = self.elastic_stress(self._u)
        return self._sigma

    @sigma.setter
    def sigma(self, value: np.ndarray) -> None:
        self._sigma = value

    def _elastic_solution(self, u: np.ndarray) -> None:
        """``u`` is the step's solution: its stress is ``D B u``, computed when read."""
        self._u, self._sigma = u, None

    def stress_at(self, q: int) -> np.ndarray:
        """The stress at quadrature point ``q``, ``(nc,)`` (Mandel, mesh frame)."""
        if self._sigma is not None:
            return self._sigma[q]
        D = self.model.D if self.model.D.ndim == 2 else self.model.D[q]
        return D.T @ (self.model.free_strain_rows(q) @ self._u)

    def strain(self, u: np.ndarray) -> np.ndarray:
        """Mandel strain at every quadrature point, ``(n_qp, nc)``, of free-dof values ``u``."""
        return (self.B @ u).reshape(self.model.n_qp, -1)

    def elastic_stress(self, u: np.ndarray) -> np.ndarray:
        """``D eps(u)`` at every quadrature point, ``(n_qp, nc)`` (:func:`.forms.elastic_stress`)."""
        return forms.elastic_stress(self.strain(u), self.model.D)

    def solve(self, rhs: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, int]:
        """Solution and iteration count (1) for the right-hand side ``rhs`` (free dofs)."""
        u = self.lu.solve(rhs)
        self._elastic_solution(u)
        return u, 1


class Plastic(Elastic):
    """Elasto-plastic equilibrium: Newton with the law's consistent tangent (von Mises: radial return).

    Converged when ``||du_i|| / ||u_i|| < tol`` (``du_i`` the Newton correction, ``u_i`` the
    displacement after it) at an iteration after the first; the first, elastic, iteration is
    final when no point yields. The material state is committed only on convergence.
    """

    def __init__(self, model, c: float, tol: float, linear_solver: str = AUTO):
        super().__init__(model, c)
        self.tol = tol
        if linear_solver not in LINEAR_SOLVERS:
            raise ValueError(f"linear_solver {linear_solver!r}: one of {', '.join(LINEAR_SOLVERS)}")
        self.linear_solver = linear_solver
        #: conjugate-gradient iterations on tangents, and tangents factorized after CG gave up
        self.cg_iterations = self.cg_fallbacks = 0

    def _return(self, u):
        with np.errstate(invalid="ignore", over="ignore", divide="ignore"):  # a diverged iterate: solve() says so
            return self.law.stress(self.strain(u), self.state)[1]

    def _tangent_lu(self, ret):
        """``K_t + c M`` ready to solve: the elastic matrix plus the yielding points' correction,
        by CG on the elastic factors or factorized (module doc)."""
        y = np.flatnonzero(ret.yielding)
        nc = ret.sigma.shape[1]
        By = self.B[(y[:, None] * nc + np.arange(nc)).ravel()]
        dD = self.law.tangent(ret)[y] - forms.at_points(self.model.D, y)
        blocks = dD * self.model.weights[y][:, None, None]

        def factorized():
            self.factorizations += 1
            try:
                return factorize(self.A + By.T @ (forms.material_blocks(dD, self.model.weights[y]) @ By))
            except RuntimeError as exc:  # SuperLU: a singular tangent (collapse without inertia)
                raise NotConverged(f"the tangent is singular ({exc}): the body has collapsed") from None

        symmetric = np.allclose(blocks, blocks.transpose(0, 2, 1), rtol=1e-12, atol=1e-12 * np.abs(blocks).max())
        if self.linear_solver == SUPERLU or (self.linear_solver == AUTO and not symmetric):
            return factorized()
        if not symmetric:
            raise NotConverged("linear_solver=pcg: the law's tangent is not symmetric; use superlu")
        return PreconditionedTangent(self.A, self.lu, By.tocsr(), blocks, factorized)

    def _count(self, lu) -> None:
        """Add a tangent's CG iterations (and a fallback to factors) to the run's counts."""
        if isinstance(lu, PreconditionedTangent):
            self.cg_iterations += lu.iterations
            self.cg_fallbacks += lu.factorized
            lu.iterations = 0

    def _residual(self, rhs, u, ret) -> np.ndarray:
        return rhs - forms.internal_forces(self.B, self.model.weights, ret.sigma) - self.c * (self.M @ u)

    def solve(self, rhs, u):
        ret = self._return(u)
        lu = self.lu
        r = self._residual(rhs, u, ret)
        first = np.linalg.norm(r) or np.inf  # no residual, no divergence to watch
        for it in range(1, MAX_ITERATIONS + 1):
            du = lu.solve(r)
            step = 1.0
            while True:
                u_new = u + step * du
                ret = self._return(u_new)
                r_new = self._residual(rhs, u_new, ret)
                # a full Newton step unless it has stalled: then halve it while that lowers the residual
                if (it <= LINE_SEARCH_AFTER or step < 2.0**-LINE_SEARCH_HALVINGS
                        or not np.linalg.norm(r_new) > np.linalg.norm(r)):
                    break
                step /= 2
            du, u, r = step * du, u_new, r_new
            if not (np.isfinite(u).all() and np.isfinite(ret.sigma).all() and np.isfinite(ret.eps_p).all()):
                # NaN compares false: a diverged iterate would otherwise pass for converged
                raise NotConverged(f"Newton diverged at iteration {it} (non-finite displacement or stress)")
            if np.linalg.norm(r) > DIVERGENCE * first:
                raise NotConverged(f"Newton diverged at iteration {it} (the residual grew {DIVERGENCE:g} times)")
            done = not ret.yielding.any() if it == 1 else np.linalg.norm(du) <= self.tol * np.linalg.norm(u)
            self._count(lu)
            if done:
                self.sigma, self.state = ret.sigma, ret
                return u, it
            lu = self._tangent_lu(ret) if ret.yielding.any() else self.lu
        raise NotConverged(f"no convergence in {MAX_ITERATIONS} iterations")
