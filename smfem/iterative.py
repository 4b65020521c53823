"""The block-iterative algorithm (13)-(15) for elasto-plastic and inhomogeneous steps.

Per time step, additional loads + Newton-Kantorovich + block successive over-relaxation over
the harmonics: every diagonal block ``K(ll) + a0 M(ll)`` is factorized once, and
``U(l) <- U(l) + omega Kt(ll)^-1 (Qt(l) - R(l))``, where ``R(l)`` holds the internal forces of
the current stresses (inhomogeneity, plasticity and all harmonic coupling enter here) plus the
inertia with the mass coupling, in Gauss-Seidel order. Within a sweep the stresses follow each
block's update elastically (15); at the end of the sweep they are recomputed from the step's
strain increment with Wilkins' correction (16). Converged when the relative change of the
amplitudes in a sweep is below ``tol``. The material state is committed only then.

A system of :func:`smfem.newmark.march`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from cases.material import lame

from .newmark import Constants, StepFailed
from .options import SolverOptions
from .plasticity import intensity, wilkins
from .sampling import SamplePoints


class NotConverged(StepFailed):
    """A time step did not converge within the allowed iterations."""


class Anderson:
    """Anderson acceleration of the fixed point ``x -> x + f(x)`` (``f`` the correction one
    elastic solve gives): the next iterate combines the last ``memory`` ones so that the
    linearized correction is least (Walker & Ni 2011, type II). The stopping test stays the
    size of the plain correction ``f``."""

    def __init__(self, memory: int):
        self.memory, self.dX, self.dF, self.last = memory, [], [], None

    def next(self, x: np.ndarray, f: np.ndarray) -> np.ndarray:
        if self.last is not None:
            self.dX.append(x - self.last[0])
            self.dF.append(f - self.last[1])
            if len(self.dX) > self.memory:
                self.dX.pop(0), self.dF.pop(0)
        self.last = (x, f)
        if not self.dX:
            return x + f
        F = np.column_stack(self.dF)
        gamma = np.linalg.lstsq(F, f, rcond=1e-12)[0]
        step = x + f - (np.column_stack(self.dX) + F) @ gamma
        return step if np.isfinite(step).all() else x + f


@dataclass
class PointState:
    """Committed material state at the sample points (n_elements, 4, n_x3, ...): stresses,
    plastic strains (Voigt) and the accumulated equivalent plastic strain."""

    sigma: np.ndarray
    eps_p: np.ndarray
    alpha: np.ndarray

    @property
    def peps(self) -> np.ndarray:
        """Plastic strain intensity sqrt(2/3 eps_p : eps_p) (what the probes report)."""
        return intensity(self.eps_p)


class BlockIterative:
    """The steps of a nonlinear SMFEM model by block SOR over the harmonics.

    Parameters
    ----------
    model : a :class:`smfem.model.Model` built with ``nonlinear=True``
    dt : time step, s
    options : relaxation (omega of the block SOR), tolerance (relative change of the amplitudes
        that ends the iterations) and the iteration limit
    coupled : ``(K, M)`` of all harmonics stacked (``M`` a sparse matrix where the mass
        couples them, else the lumped diagonal), to iterate with one solve of all harmonics
        instead of the block sweep: the whole coupled elastic system where the material varies
        along x3, the block-diagonal one where it does not (then the sweep is block Jacobi in
        exact arithmetic anyway: the harmonics do not couple through the stiffness)
    """

    def __init__(self, model, dt: float, options: SolverOptions, coupled: tuple | None = None):
        self.model, self.omega, self.memory = model, options.relaxation, options.anderson
        self.tol, self.max_iter = options.tolerance_for(model.case), options.max_iterations
        self.c = Constants.of(dt)
        self.points = SamplePoints(model)
        self.split = lambda x: np.split(x, self.points.offsets[1:-1])
        S = model.systems
        if coupled is None:
            self.lu = [sla.splu((s.K + sp.diags(self.c.a0 * s.M)).tocsc()) for s in S]
            self.coupled_lu = None
        else:
            # the stacked elastic K + a0 M as the iteration matrix: all harmonics at once
            K, self.M = coupled
            a0M = sp.diags(self.c.a0 * self.M) if isinstance(self.M, np.ndarray) else self.c.a0 * self.M
            self.coupled_lu = sla.splu((K + a0M).tocsc())
            self.Q = np.concatenate([s.Q for s in S])
        self.factorizations = len(S) if coupled is None else 1
        # each mode's rows of the mass coupling rho(lm), l != m, acting on all modes stacked
        o = model.offsets
        self.mass_rows = [model.coupled_mass[o[i]:o[i + 1]] for i in range(len(S))] if model.coupling else None
        mat = model.case.material
        self.plastic = mat.plastic
        self.sigma_y0, self.H = mat.sigma_y, mat.hardening_modulus
        f = model.factor[:, None, :]  # the contrast material's stiffness is scaled
        self.mu = lame(mat.E, mat.nu)[1] * np.broadcast_to(f, (len(f), 4, f.shape[2]))
        self.state = PointState(np.zeros(self.mu.shape + (6,)), np.zeros(self.mu.shape + (6,)), np.zeros(self.mu.shape))
        self.timings = {"synthesis": 0.0, "stress": 0.0, "projection": 0.0, "solves": 0.0}

    def inertia(self, i: int, new: list[np.ndarray], predicted: list[np.ndarray]) -> np.ndarray:
        """Row ``i`` of ``M a`` with ``a = a0 (u - u_predicted)``, the mass coupling included."""
        out = self.model.systems[i].M * (new[i] - predicted[i])
        if self.mass_rows is not None:
            out = out + self.mass_rows[i] @ (np.concatenate(new) - np.concatenate(predicted))
        return self.c.a0 * out

    @property
    def peps(self) -> np.ndarray:
        return self.state.peps

    def initial_acceleration(self, u0: np.ndarray) -> np.ndarray:
        """``M a = Q - R(u0)``, the stresses of ``u0`` taken as the state at t = 0."""
        S = self.model.systems
        self.state = PointState(self.points.stress(self.split(u0)), self.state.eps_p, self.state.alpha)
        force = np.concatenate([s.Q for s in S]) - self.points.forces(self.state.sigma)
        if self.model.coupling:
            return sla.spsolve(self.model.mass_matrix().tocsc(), force)
        return force / np.concatenate([s.M for s in S])

    def commit(self, u: np.ndarray) -> None:
        self.state = self.pending

    def observe(self, state) -> None:
        """Nothing to watch between steps."""

    def report(self) -> tuple[str, dict]:
        return "", {"n_x3_points": len(self.model.x3), "time_breakdown_s": dict(self.timings)}

    def solve(self, predicted: np.ndarray, u: np.ndarray, step_index: int, t: float) -> tuple[np.ndarray, int]:
        """One time step's iterations from the last step's ``u``; the new amplitudes and the
        number of iterations (the material state waits for :meth:`commit`)."""
        S, c, pts = self.model.systems, self.c, self.points
        tick = time.perf_counter
        predicted, u = self.split(predicted), self.split(u)
        new = [ui.copy() for ui in u]
        sigma = self.state.sigma.copy()
        anderson = Anderson(self.memory) if self.memory and self.coupled_lu is not None else None
        for iteration in range(1, self.max_iter + 1):
            change2 = 0.0
            if self.coupled_lu is not None:
                t0 = tick()
                x, p = np.concatenate(new), np.concatenate(predicted)
                r = self.Q - pts.forces(sigma) - c.a0 * (self.M * (x - p) if isinstance(self.M, np.ndarray)
                                                         else self.M @ (x - p))
                t1 = tick()
                du = self.coupled_lu.solve(r)
                self.timings["projection"] += t1 - t0
                self.timings["solves"] += tick() - t1
                new = np.split(x + du if anderson is None else anderson.next(x, du), pts.offsets[1:-1])
                change2 = du @ du
            for i, s in enumerate(S if self.coupled_lu is None else ()):
                t0 = tick()
                r = s.Q - pts.force_of_mode(i, sigma) - self.inertia(i, new, predicted)
                t1 = tick()
                du = self.omega * self.lu[i].solve(r)
                t2 = tick()
                new[i] = new[i] + du
                sigma = sigma + pts.stress_of_mode(i, du)  # (15): elastic within the sweep
                t3 = tick()
                self.timings["projection"] += t1 - t0
                self.timings["solves"] += t2 - t1
                self.timings["synthesis"] += t3 - t2
                change2 += du @ du
            t0 = tick()
            trial = self.state.sigma + pts.stress(np.concatenate(new) - np.concatenate(u))
            t1 = tick()
            if self.plastic:
                sigma, alpha, deps_p, _ = wilkins(trial, self.state.alpha, self.mu, self.sigma_y0, self.H)
            else:
                sigma, alpha, deps_p = trial, self.state.alpha, 0.0
            self.timings["synthesis"] += t1 - t0
            self.timings["stress"] += tick() - t1
            size2 = sum(x @ x for x in new)
            if not (np.isfinite(change2) and np.isfinite(size2)):
                raise NotConverged(f"step {step_index} (t = {t:.6g} s) diverged at iteration {iteration}: "
                                   f"the amplitudes are no longer finite")
            if change2 <= self.tol**2 * max(size2, 1e-300):
                self.pending = PointState(sigma, self.state.eps_p + deps_p, alpha)
                return np.concatenate(new), iteration
        raise NotConverged(
            f"step {step_index} (t = {t:.6g} s) did not converge in {self.max_iter} iterations "
            f"(relative change {np.sqrt(change2 / max(size2, 1e-300)):.3g}, tol {self.tol:g})"
        )
