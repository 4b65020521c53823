"""Newmark time stepping (paper (9)-(11)) of any SMFEM system, as one generator over steps.

Every step of every scene is the same predictor and corrector; what differs is how the
step's equilibrium is solved, which a *system* does:

* ``initial_acceleration(u0)``: ``a`` at t = 0 from ``M a = Q - R(u0)`` (the load is on at t = 0);
* ``solve(predicted, u, step, t)``: the displacement ``u_new`` and the iterations it took, where
  the step's inertia is ``M a0 (u_new - predicted)``; raises :class:`StepFailed`;
* ``commit(u_new)``: the step converged; its material or contact state becomes the next
  step's start;
* ``observe(state)``: after every state the run records (t = 0 included);
* ``report()``: at the end, a verdict on the whole run (``''`` if none) and facts for ``info``.

:class:`LinearSystem` (assembled matrices, one factorization), :class:`CoupledLinearSystem`
(harmonics that couple, applied without the coupled matrix and solved by a form of
:mod:`smfem.coupled_solve`), :class:`smfem.iterative.BlockIterative` (plastic steps) and
:class:`smfem.contact.ContactSystem` (the contact layer) are the four.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from cases.timeint import ALPHA, DELTA

from .linalg import BlockFactors, factorize_spd


class StepFailed(RuntimeError):
    """A time step that could not be solved; the steps before it stand."""


@dataclass(frozen=True)
class Constants:
    """Newmark constants of one time step, in the paper's notation (9)-(11)."""

    dt: float
    a0: float
    a2: float
    a3: float
    a6: float
    a7: float

    @classmethod
    def of(cls, dt: float, alpha: float = ALPHA, delta: float = DELTA) -> "Constants":
        return cls(dt, a0=1.0 / (alpha * dt * dt), a2=1.0 / (alpha * dt), a3=0.5 / alpha - 1.0,
                   a6=dt * (1.0 - delta), a7=delta * dt)


@dataclass
class State:
    """Displacement, velocity and acceleration (all modes stacked) after step ``n``, and the
    iterations the step took (0 at t = 0)."""

    n: int
    u: np.ndarray
    v: np.ndarray
    a: np.ndarray
    iterations: int = 0


def march(system, u0: np.ndarray, v0: np.ndarray, dt: float, n_steps: int) -> Iterator[State]:
    """Yield the state at t = 0, then after each of ``n_steps`` steps (:class:`StepFailed`
    from ``system.solve`` ends it)."""
    c = Constants.of(dt)
    # a0 u + a2 v + a3 a = a0 (u + b1 v + b2 a): the same right-hand side in fewer operations
    b1, b2 = c.a2 / c.a0, c.a3 / c.a0
    state = State(0, u0.copy(), v0.copy(), system.initial_acceleration(u0))
    yield state
    for n in range(1, n_steps + 1):
        predicted = state.u + b1 * state.v + b2 * state.a
        u, iterations = system.solve(predicted, state.u, n, n * dt)
        system.commit(u)
        a = c.a0 * (u - predicted)  # = a0 (u - u_t) - a2 v - a3 a
        state = State(n, u, state.v + c.a6 * state.a + c.a7 * a, a, iterations)
        yield state


class Load:
    """A load history ``Q + sum Q_k(t)``: the pressures' ``Q``, held from t = 0, and the timed
    loads ``Q_k(t)`` (callables: force terms, pressures with an amplitude or moving; all modes
    stacked, :func:`smfem.stacking.force_terms`)."""

    def __init__(self, Q: np.ndarray, terms=()):
        self.Q, self.terms = Q, tuple(terms)

    def __call__(self, t: float) -> np.ndarray:
        return self.Q + sum(term(t) for term in self.terms) if self.terms else self.Q


class MassSolve:
    """``M^-1 f`` on the dofs that have mass, zero on the massless ones: a 9-node element's nodes
    on the axis (:attr:`smfem.quad9.Quad9Operators.node_volume`), a contact face's
    (:func:`smfem.contact.face_free_mass`), whose motion follows the rest quasi-statically (their
    acceleration enters no inertia force). ``M``: a diagonal (n,) or a sparse mass, whose
    massless rows are empty; its massive block is factorized once."""

    def __init__(self, M):
        self.diagonal = isinstance(M, np.ndarray) and M.ndim == 1
        self.massive = (M if self.diagonal else M.diagonal()) > 0
        if self.diagonal:
            self.M = M
        else:
            block = sp.csc_matrix(sp.csr_matrix(M)[self.massive][:, self.massive])
            self.lu = sla.splu(block)

    def __call__(self, f: np.ndarray) -> np.ndarray:
        if self.diagonal:
            return np.divide(f, self.M, out=np.zeros_like(f), where=self.massive)
        out = np.zeros_like(f)
        out[self.massive] = self.lu.solve(f[self.massive])
        return out


def acceleration_at_rest(mass, force: np.ndarray) -> np.ndarray:
    """``M a = force`` at t = 0 (:class:`MassSolve`), ``mass()`` giving ``M`` asked for only
    where the force is not zero: a body that starts at rest and unloaded (the moving loads) needs
    neither a coupled mass (every pair of modes at every cut-out dof) nor its factorization."""
    return MassSolve(mass())(force) if force.any() else np.zeros_like(force)


class LinearSystem:
    """``M a + K u = Q`` with one factorization of ``K + a0 M`` per time-step size.

    Parameters
    ----------
    K : (n, n) sparse stiffness (block-diagonal over decoupled modes, or the coupled system)
    M : (n,) lumped mass diagonal, or (n, n) sparse mass where harmonics couple through rho(lm)
    Q : (n,) load held from t = 0
    dt : time step, s
    terms : callables ``t -> Q_k(t)`` added to ``Q`` (loads varying in time, :class:`Load`)
    blocks : (n_blocks + 1,) offsets of the diagonal blocks of a block-diagonal ``K`` with a
        lumped ``M`` (decoupled harmonics), each factorized apart; None: the matrix whole
    """

    def __init__(self, K: sp.spmatrix, M, Q: np.ndarray, dt: float, terms=(), blocks: np.ndarray | None = None):
        self.K, self.load, self.blocks = K.tocsr(), Load(Q, terms), blocks
        self.diagonal_mass = isinstance(M, np.ndarray) and M.ndim == 1
        self.M = M if self.diagonal_mass else sp.csr_matrix(M)
        self.lu = self.factorize(dt)
        self.factorizations = 1

    def factorize(self, dt: float):
        """The factorization of the step's matrix ``K + a0 M`` (symmetric positive definite:
        :func:`smfem.linalg.factorize_spd`)."""
        self.a0M = Constants.of(dt).a0 * self.M
        return self.step_factors(self.a0M, factorize_spd)

    def step_factors(self, scaled_mass, factorize):
        """``factorize(K + scaled_mass)`` (``scaled_mass`` a multiple of ``M``), or with ``blocks``
        each diagonal block's (:class:`smfem.linalg.BlockFactors`)."""
        if self.blocks is None:
            return factorize(self.K + self.mass_matrix(scaled_mass))
        o = self.blocks
        return BlockFactors((self.K[a:b, a:b] + sp.diags(scaled_mass[a:b]) for a, b in zip(o[:-1], o[1:])), factorize)

    def mass_matrix(self, scaled_mass) -> sp.spmatrix:
        """``scaled_mass`` (a multiple of ``M``, diagonal or sparse as ``M`` is) as a sparse matrix."""
        return sp.diags(scaled_mass) if self.diagonal_mass else scaled_mass

    def initial_acceleration(self, u0: np.ndarray) -> np.ndarray:
        return MassSolve(self.M)(self.load(0.0) - self.K @ u0)

    def solve(self, predicted: np.ndarray, u: np.ndarray, step: int, t: float) -> tuple[np.ndarray, int]:
        """``(K + a0 M) u = Q + a0 M predicted``."""
        return self.lu.solve(self.load(t) + (self.a0M * predicted if self.diagonal_mass else self.a0M @ predicted)), 1

    def commit(self, u: np.ndarray) -> None:
        """Nothing to keep: the system has no state."""

    def observe(self, state: State) -> None:
        """Nothing to watch between steps."""

    def report(self) -> tuple[str, dict]:
        return "", {}

    def energy(self, u: np.ndarray, v: np.ndarray) -> tuple[float, float]:
        """Kinetic and strain energy ``(v'Mv/2, u'Ku/2)``."""
        return 0.5 * v @ self.mass_times(v), 0.5 * u @ (self.K @ u)

    def mass_times(self, x: np.ndarray) -> np.ndarray:
        """``M x`` (``x`` real or complex)."""
        return self.M * x if self.diagonal_mass else self.M @ x


class CoupledLinearSystem(LinearSystem):
    """``M a + K u = Q`` of modes that couple: ``K`` and ``M`` applied by ``op``
    (:class:`smfem.coupling.StackedOperator`: exact, no coupled matrix), ``K + a0 M`` solved by
    ``solver`` (:mod:`smfem.coupled_solve`, built for this ``dt``); ``M`` also as the sparse
    coupled mass (``mass()``, made when asked), for the acceleration at t = 0."""

    def __init__(self, op, solver, mass, Q: np.ndarray, dt: float, terms=()):
        self.op, self.lu, self.mass, self.load = op, solver, mass, Load(Q, terms)
        self.a0, self.factorizations = Constants.of(dt).a0, 1

    def initial_acceleration(self, u0: np.ndarray) -> np.ndarray:
        return acceleration_at_rest(self.mass, self.load(0.0) - self.op.K(u0))

    def solve(self, predicted: np.ndarray, u: np.ndarray, step: int, t: float) -> tuple[np.ndarray, int]:
        return self.lu.solve(self.load(t) + self.a0 * self.op.M(predicted)), 1

    def energy(self, u: np.ndarray, v: np.ndarray) -> tuple[float, float]:
        return 0.5 * v @ self.op.M(v), 0.5 * u @ self.op.K(u)

    def mass_times(self, x: np.ndarray) -> np.ndarray:
        return self.op.M(x)
