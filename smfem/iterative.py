"""The block-iterative algorithm (13)-(16) for elasto-plastic and inhomogeneous steps.

Per time step the additional-loads method: the plastic strains act as loads on the elastic
body, ``K u + a0 M (u - u_pred) = Q + F_p(eps_p)`` with ``F_p = int B' f D eps_p``, and each
iteration solves the elastic system with the residual of the current iterate,
``u <- u + A^-1 (Q + F_p - K u - a0 M (u - u_pred))``. ``K`` and ``M`` are applied exactly,
the harmonic coupling of the cut-outs included (:class:`smfem.coupling.StackedOperator`);
the plastic strains live at the sample points (:mod:`smfem.sampling`), where the trial
stresses, the elastic stress of the iterate less the committed relaxed stress (the stress of
the step's displacement increment from the committed state), go through the material's law
(:mod:`smfem.laws`; von Mises: returned to the yield surface by Wilkins' correction (16)). After
a step's first iteration only the points that the change since its first iterate may carry past
the yield surface are visited (:mod:`smfem.screening`). ``A``, the iteration
matrix, is one of three: the whole coupled ``K + a0 M`` solved directly (:class:`Factorized`, a
form of :mod:`smfem.coupled_solve`; exact for an elastic step: one iteration and a check), the
same system by conjugate gradients with the diagonal blocks as preconditioner
(:class:`ConjugateGradients`, to a relative residual of 1e-3: the outer iterations do the
rest), or the paper's block SOR over the harmonics (:class:`BlockSOR`), where within a sweep
the stresses follow each block's update elastically (15). Anderson acceleration (Walker & Ni 2011) combines the last iterates. A step has converged when the
correction of an iteration, ``A^-1`` times the residual, is below ``tol`` relative to the
amplitudes; the material state is committed only then.

A system of :func:`smfem.newmark.march`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from cases import x3_points

from . import laws
from .coupling import StackedOperator
from .linalg import BlockFactors, block_diagonal, step_blocks
from .newmark import Constants, Load, StepFailed, acceleration_at_rest
from .options import SolverOptions
from .sampling import SamplePoints
from .screening import Screen


#: the share of the points above which the iterations after a step's first visit every point,
#: not those the screen leaves (:mod:`smfem.screening`), for the rest of the step: the notched
#: strip's hinge, whose bound leaves 70 % of the points, is cheaper whole
SCREEN_SHARE = 0.3

#: relative residual to which conjugate gradients solve a correction ('matrix-free'), and their
#: iteration limit: the outer iterations converge by this factor each, so it need not be tight
KRYLOV_RTOL, KRYLOV_MAX = 1e-3, 500


@dataclass
class FirstIterate:
    """A step's first iterate ``x`` and its trial stresses, against which the step's later
    iterations are screened (:mod:`smfem.screening`); ``room``, the trials' headroom, is made
    when a second iteration asks for it (an elastic step has none)."""

    x: np.ndarray
    trial: np.ndarray
    room: np.ndarray | None = None


@dataclass(frozen=True)
class Step:
    """The step being solved: its load ``Q``, the predicted displacement and what applies
    ``K`` and ``M``; the iterations add the plastic loads."""

    Q: np.ndarray
    predicted: np.ndarray
    op: StackedOperator
    a0: float

    @cached_property
    def rhs(self) -> np.ndarray:
        """``Q + a0 M predicted``: the right-hand side but the plastic loads."""
        return self.Q + self.a0 * self.op.M(self.predicted)

    def residual(self, x: np.ndarray, loads: np.ndarray) -> np.ndarray:
        return self.Q + loads - self.op.K(x) - self.a0 * self.op.M(x - self.predicted)


class Factorized:
    """The iteration matrix ``A = K + a0 M`` itself, solved directly (a form of
    :mod:`smfem.coupled_solve`): ``x + A^-1 (b - A x) = A^-1 b`` without ``K x``, and exact."""

    exact = True

    def __init__(self, solver):
        self.solver, self.factorizations = solver, 1
        self.factors = [solver]  # what one iteration solves with

    def correction(self, x: np.ndarray, step: Step, loads: np.ndarray) -> np.ndarray:
        return self.solver.solve(step.rhs + loads) - x


class ConjugateGradients:
    """``A`` by conjugate gradients (:class:`smfem.coupled_solve.Krylov`), each correction to
    :data:`KRYLOV_RTOL` from zero."""

    exact = False

    def __init__(self, krylov):
        self.krylov, self.factorizations = krylov, len(krylov.diagonal.factors)
        self.factors = krylov.diagonal.factors  # one solve each per Krylov iteration

    def correction(self, x: np.ndarray, step: Step, loads: np.ndarray) -> np.ndarray:
        return self.krylov.solve(step.residual(x, loads), start=np.zeros_like(x))


class BlockSOR:
    """The paper's block SOR over the harmonics: one sweep, each block's update followed
    elastically by the next (15); exact where the blocks do not couple and ``omega`` is 1."""

    def __init__(self, model, a0: float, omega: float):
        S, o = model.systems, model.offsets
        self.omega, self.offsets = omega, o
        self.lus = BlockFactors(step_blocks(((s.K, s.M) for s in S), a0)).factors
        K = block_diagonal([s.K for s in S]) + (model.coupled_stiffness() if model.coupling else 0)
        M = model.mass_matrix()
        M = sp.csr_matrix(sp.diags(M) if isinstance(M, np.ndarray) else M)
        self.rows = [(sp.csr_matrix(K[o[i]:o[i + 1]]), sp.csr_matrix(a0 * M[o[i]:o[i + 1]])) for i in range(len(S))]
        self.exact = not model.coupling and omega == 1.0
        self.factors = self.lus  # one solve each per sweep
        self.factorizations = len(self.lus)

    def correction(self, x: np.ndarray, step: Step, loads: np.ndarray) -> np.ndarray:
        o, new = self.offsets, x.copy()
        for i, (lu, (K, a0M)) in enumerate(zip(self.lus, self.rows)):
            r = step.Q[o[i]:o[i + 1]] + loads[o[i]:o[i + 1]] - K @ new - a0M @ (new - step.predicted)
            new[o[i]:o[i + 1]] += self.omega * lu.solve(r)
        return new - x


class NotConverged(StepFailed):
    """A time step did not converge within the allowed iterations."""


class Anderson:
    """Anderson acceleration of the fixed point ``x -> x + f(x)`` (``f`` the correction one
    solve gives): the next iterate combines the last ``memory`` ones so that the linearized
    correction is least (Walker & Ni 2011, type II).

    The differences are kept in two ring buffers, and the least squares problem is solved by its
    normal equations, kept up to date one column at a time, on unit columns, their eigenvalues
    below 1e-14 of the largest left out (a least squares solve of the whole (n, memory) matrix
    each iteration, LAPACK's ``gelsd`` on stacked copies, took 0.37 and 2.5 ms at 5,040 and
    40,000 unknowns and memory 5, the normal equations 0.10 and 0.61 ms, on a loaded host)."""

    #: eigenvalues of the scaled normal matrix below this share of the largest are left out
    #: (the columns' rcond ~1e-7: the iteration's tolerance is far above what they would add)
    CUTOFF = 1e-14

    def __init__(self, memory: int):
        self.memory, self.last, self.count = memory, None, 0
        self.dX = self.dF = None
        self.G = np.zeros((memory, memory))

    def next(self, x: np.ndarray, f: np.ndarray) -> np.ndarray:
        if self.memory == 0:
            return x + f
        if self.last is not None:
            if self.dX is None:
                self.dX, self.dF = np.empty((len(x), self.memory), order="F"), np.empty((len(x), self.memory), order="F")
            col = self.count % self.memory
            np.subtract(x, self.last[0], out=self.dX[:, col])
            np.subtract(f, self.last[1], out=self.dF[:, col])
            self.count += 1
            k = min(self.count, self.memory)
            self.G[col, :k] = self.G[:k, col] = self.dF[:, :k].T @ self.dF[:, col]
        self.last = (x, f)
        k = min(self.count, self.memory)
        if k == 0:
            return x + f
        F, G = self.dF[:, :k], self.G[:k, :k]
        norm = np.sqrt(np.diag(G))
        norm = np.where(norm > 0, norm, 1.0)
        lam, V = np.linalg.eigh(G / np.outer(norm, norm))
        keep = lam > self.CUTOFF * lam[-1]
        if not keep.any():
            return x + f
        V = V[:, keep]
        gamma = V @ ((V.T @ ((F.T @ f) / norm)) / lam[keep]) / norm
        step = x + f - self.dX[:, :k] @ gamma - F @ gamma
        return step if np.isfinite(step).all() else x + f


@dataclass
class PointState:
    """Committed state at the sample points: the law's (its plastic strains and whatever else
    it keeps; not its stresses, which the iterations make from the amplitudes) and ``relaxed =
    f D eps_p`` (6, n_points), the stress the inelastic strains took off, whose forces are the
    additional loads: the stress at the points is ``stress(u) - relaxed``."""

    law: object
    relaxed: np.ndarray


class BlockIterative:
    """The steps of a nonlinear SMFEM model by the additional-loads iterations.

    Parameters
    ----------
    model : a :class:`smfem.model.Model`
    dt : time step, s
    options : Anderson memory, tolerance, iteration limit and sample points along x3
    iteration : the iteration matrix (:class:`Factorized`, :class:`ConjugateGradients` or
        :class:`BlockSOR`, built for ``dt``; :mod:`smfem.strategy` chooses it)
    op : ``K`` and ``M`` of the modes stacked, applied
    terms : the timed loads (:class:`smfem.newmark.Load`)
    """

    def __init__(self, model, dt: float, options: SolverOptions, iteration, op: StackedOperator, terms=()):
        self.model, self.iteration, self.op = model, iteration, op
        self.memory = options.anderson if not isinstance(iteration, BlockSOR) else 0
        self.tol, self.max_iter = model.case.params["tol"], options.max_iterations
        self.c = Constants.of(dt)
        self.x3_rule = (options.x3_oversampling, "set") if options.x3_oversampling is not None else \
            x3_points.oversampling(model.case.name, model.case.params.get("harmonics", 0))
        self.points = SamplePoints(model, self.x3_rule[0], options.x3_min_points)
        self.offsets = model.offsets
        self.Q = np.concatenate([s.Q for s in model.systems])
        #: the load history (the force terms' time functions over the held pressures)
        self.load = Load(self.Q, terms)
        self.factorizations = iteration.factorizations
        n_points = int(np.prod(self.points.point_shape[1:]))
        # the contrast material's stiffness is scaled with its factor
        factor = np.broadcast_to(self.points.factor[:, None, :], self.points.point_shape[1:]).ravel()
        index = np.broadcast_to(model.material_index[:, None, None], self.points.point_shape[1:]).ravel()
        self.law = laws.for_points(model.case.materials, index, factor)
        self.state = PointState(self.law.initial_state(n_points), np.zeros((6, n_points)))
        #: which points the iterations after a step's first visit, where the law can tell how far
        #: a trial is from leaving its elastic range (:mod:`smfem.screening`); else every point
        self.screen = Screen(self.points) if hasattr(self.law, "stress_at") else None
        self.loads = np.zeros_like(self.Q)  # the committed additional loads F_p
        self.loads_before = self.loads
        #: the converged step's point state and loads, which :meth:`commit` makes the state
        self.pending: tuple[PointState, np.ndarray] | None = None
        self._peps = None  # :attr:`peps_sampled` of the committed state, once asked
        self.timings = {"synthesis": 0.0, "stress": 0.0, "projection": 0.0, "solves": 0.0}

    @property
    def peps_sampled(self) -> np.ndarray:
        """Plastic strain intensity sqrt(2/3 eps_p : eps_p) at the sample points only (the
        fundamental domain along x3), (ne, section points, n_x3); :attr:`peps_images` maps
        :attr:`peps_x3` onto them."""
        if self._peps is None:
            self._peps = self.law.equivalent_plastic_strain(self.state.law)
        return self._peps.reshape(self.points.point_shape[1:])

    @property
    def peps_images(self) -> np.ndarray:
        """For each point of :attr:`peps_x3`, the sample point it is an image of."""
        return self.points.images[1]

    @property
    def peps(self) -> np.ndarray:
        """:attr:`peps_sampled` over the whole x3 range (:attr:`peps_x3`), (ne, section points, n)."""
        return self.points.unfolded(self.peps_sampled)[1]

    @property
    def relaxed(self) -> np.ndarray:
        """The stress the plastic strains took off, element means, rows first, over the whole
        x3 range (:attr:`peps_x3`): (6, ne, n)."""
        return self.points.unfolded(self.state.relaxed.reshape(self.points.point_shape).mean(axis=2), rows=True)[1]

    @property
    def peps_x3(self) -> np.ndarray:
        """The x3 of the points of :attr:`peps` (the sample points and their images)."""
        return self.points.unfolded(self.points.x3)[0]

    def initial_acceleration(self, u0: np.ndarray) -> np.ndarray:
        """``M a = Q - K u0`` (no plastic strain at t = 0; ``u0`` is elastic)."""
        force = self.load(0.0) - self.op.K(u0)
        mass = self.model.mass_matrix if self.model.coupling else lambda: self.op.M_h
        return acceleration_at_rest(mass, force)

    def commit(self, u: np.ndarray) -> None:
        self.loads_before = self.loads
        self.state, self.loads = self.pending
        self.pending = None
        # a step changes the plastic strain at its yielding points only: the probes ask every step
        at = self.state.law.yielding
        if self._peps is not None and len(at):
            if hasattr(self.law, "equivalent_plastic_strain_at"):
                self._peps = self._peps.copy()
                self._peps[at] = self.law.equivalent_plastic_strain_at(self.state.law, at)
            else:
                self._peps = None

    def observe(self, state) -> None:
        """Nothing to watch between steps."""

    def report(self) -> tuple[str, dict]:
        facts = {"n_x3_points": len(self.points.x3), "x3_oversampling": self.x3_rule[0], "x3_rule": self.x3_rule[1],
                 "time_breakdown_s": dict(self.timings)}
        if isinstance(self.iteration, ConjugateGradients):
            facts["krylov_iterations"] = self.iteration.krylov.iterations
        return "", facts

    def solve(self, predicted: np.ndarray, u: np.ndarray, step_index: int, t: float) -> tuple[np.ndarray, int]:
        """One time step's iterations from the last step's ``u``; the new amplitudes and the
        number of iterations (the material state waits for :meth:`commit`)."""
        tick, pts, state = time.perf_counter, self.points, self.state
        step = Step(self.load(t), predicted, self.op, self.c.a0)
        anderson = Anderson(self.memory) if self.memory else None
        # the plastic loads extrapolated from the last two steps: a closer start (strip: 5.8 -> 5.0
        # iterations per step); the iterations recompute them from the state, so only the start moves
        x = u
        loads = start = 2 * self.loads - self.loads_before
        first: FirstIterate | None = None
        for iteration in range(1, self.max_iter + 1):
            t0 = tick()
            dx = self.iteration.correction(x, step, loads)
            x = x + dx if anderson is None else anderson.next(x, dx)
            t1 = tick()
            visited = None
            if first is not None:  # only where the change since the first iterate may reach the yield surface
                if first.room is None:
                    first.room = self.screen.room(self.law.headroom(first.trial, state.law))
                moved = x - first.x
                coefficients = pts.series.coefficients(moved)
                visited = self.screen.at_risk(coefficients, first.room)
                if len(visited) > SCREEN_SHARE * first.trial.shape[1]:
                    visited = first = None  # most of the body: every point, for the rest of the step
            if visited is None:
                # the stress of the amplitudes less what the plastic strains took off: the trial
                # of a step from the committed state, made from the amplitudes alone
                trial = pts.stress(x).reshape(6, -1) - state.relaxed
                t2 = tick()
                sigma, law_state = self.law.stress(trial, state.law)
                if iteration == 1 and self.screen is not None:
                    first = FirstIterate(x, trial)
            else:
                trial = np.take(first.trial, visited, axis=1) + pts.stress_at(moved, visited, coefficients)
                t2 = tick()
                sigma, law_state = self.law.stress_at(trial, state.law, visited)
            t3 = tick()
            loads, at = self.loads, law_state.yielding
            if len(at):
                # the yielding points' rows of trial and sigma (those of ``visited`` where it is set)
                local = at if visited is None else np.searchsorted(visited, at)
                change = np.take(trial, local, axis=1) - np.take(sigma, local, axis=1)  # = f D d_eps_p
                # the forces are linear in the relaxed stress: the committed ones plus those of
                # the step's change, which is at the yielding points only
                loads = self.loads + pts.forces_at(change, at)
            t4 = tick()
            self.timings["solves"] += t1 - t0
            self.timings["synthesis"] += t2 - t1
            self.timings["stress"] += t3 - t2
            self.timings["projection"] += t4 - t3
            change2, size2 = dx @ dx, x @ x
            if not (np.isfinite(change2) and np.isfinite(size2)):
                raise NotConverged(f"step {step_index} (t = {t:.6g} s) diverged at iteration {iteration}: "
                                   f"the amplitudes are no longer finite")
            # an exact solve (the iteration matrix's ``exact``; no Anderson mixing yet) with the loads
            # that the state now gives back is the step's exact solution: no second iteration
            # to confirm it (every elastic step: the thick cylinder's first 35 of 100)
            exact = self.iteration.exact and iteration == 1 and np.array_equal(loads, start)
            if exact or change2 <= self.tol**2 * max(size2, 1e-300):
                relaxed = state.relaxed  # the relaxed stress the converged iteration leaves
                if len(at):
                    relaxed = relaxed.copy()
                    relaxed[:, at] += change
                self.pending = (PointState(law_state, relaxed), loads)
                return x, iteration
        raise NotConverged(
            f"step {step_index} (t = {t:.6g} s) did not converge in {self.max_iter} iterations "
            f"(relative change {np.sqrt(change2 / max(size2, 1e-300)):.3g}, tol {self.tol:g})"
        )
