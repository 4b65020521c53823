"""Explicit central differences on the lumped mass: the truth engine of plastic and contact scenes.

Implicit Newmark on a plastic scene under a step load converges in time at order 0.5 ... 0.85
in the max-norm, so a time-step ladder leaves its own time error as the largest part of a
truth's uncertainty. Central differences at a fraction of the critical step ``2 / omega_max``
leave a time error below the space error, and one that shrinks with it: the step is tied to
the mesh (h / c), so the time error falls as h^2 down a mesh ladder and the ladder's
extrapolation takes it along. Measured on the elastic thick cylinder (r1, against the exact
modal response of the same matrices): 0.19-0.36 % at half the critical step, the accumulated
phase error of the low modes over 6 periods; 0.03-0.08 % at a quarter of it (the step of
r4), 0.01-0.03 % at an eighth (r8). A step costs a sparse product and a radial return,
with no factorization and no Newton iteration, so the mesh ladder can go finer.

Scheme (velocity form; Belytschko, Liu & Moran, *Nonlinear Finite Elements*, box 6.1)::

    a_n = M^-1 (Q - f_int(u_n) + f_c,n)
    v_n+1/2 = v_n-1/2 + dt a_n          (v_1/2 = v_0 + dt / 2 a_0)
    u_n+1 = u_n + dt v_n+1/2
    v_n = v_n-1/2 + dt / 2 a_n

``M`` is the HRZ-lumped mass (:func:`reference_fem.mass.lumped_mass`); ``f_int`` is ``K u``
(elastic) or ``B^T w sigma`` with the radial return from the committed state at every step
(the strain increment of one step is small: no iteration, the state is committed at once).

In a body of several materials (``case.regions``) ``K``, ``M`` and the law are each element's
own, so ``omega_max``, the largest eigenvalue of the pair, is set by the stiffest and fastest
material where its elements are smallest (no wave-speed estimate from one material).

A rigid wall is a kinematic constraint (the forward-increment Lagrange multiplier of
Carpenter, Taylor & Katona 1991): a face node predicted through the wall is put back onto it
along the wall's normal. With a diagonal mass that is the exact multiplier of the constraint,
``f_c = M du / dt^2``, and a node leaves the wall when its prediction does (no tension).
Frictionless walls only.

Contact pairs between bodies (:mod:`reference_fem.pairs`: node ``i`` of a face and node ``j``
across it) are the same constraint on the relative displacement: a pair predicted through each
other (``g = g0 + n . (u_j - u_i) < 0``) is put back to touching by the impulse that does it,
``P = -g / (1 / m_i + 1 / m_j)`` (times dt^2), which moves ``i`` by ``-n P / m_i`` and ``j`` by
``n P / m_j``: the split by the two lumped masses that keeps the momentum (a node held along
the normal by a support counts as of infinite mass). With friction the closed pairs' predicted
relative slip over the step is taken back the same way, by a tangential impulse bounded by
``f P`` (stick below it, slip at it: Coulomb), so momentum is kept too.
"""

from __future__ import annotations

import functools
import time
from typing import Callable, Iterator

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from cases.params import UnsupportedCase, newmark_only
from cases.result import RunResult

from . import forms
from .face import plane_face, tangent_bases
from .frames import AXISYMMETRIC
from .mesh import build_mesh
from .model import INTORDER, Model
from .pairs import all_pairs
from .probes import Probes
from .wall import initial_gaps

#: the time step as a fraction of the critical step 2 / omega_max
SAFETY = 0.5
#: relative accuracy of the largest eigenvalue (Lanczos converges to it from below)
EIGEN_TOL = 1e-6


def largest_frequency(K: sp.spmatrix, m: np.ndarray) -> float:
    """``omega_max``, rad/s: the largest eigenvalue of ``K phi = omega^2 diag(m) phi`` (free dofs)."""
    scale = sp.diags(1.0 / np.sqrt(m))
    A = (scale @ K @ scale).tocsr()
    if A.shape[0] < 3:
        return float(np.sqrt(np.linalg.eigvalsh(A.toarray()).max()))
    v0 = np.ones(A.shape[0])  # a fixed start vector: the same step on every run
    w2 = sla.eigsh(A, k=1, which="LA", tol=EIGEN_TOL, v0=v0, return_eigenvectors=False)[0]
    return float(np.sqrt(w2))


def refuse(case) -> None:
    """What the engine cannot take, in one line (:class:`cases.UnsupportedCase`), before any work:
    another time scheme's option, a rigid wall with plasticity or with friction."""
    newmark_only(case, "explicit reference")
    if case.wall is not None and case.material.plastic:
        raise UnsupportedCase("explicit reference: contact with plasticity is not available")
    if case.wall is not None and case.wall.friction > 0:
        raise UnsupportedCase("explicit reference: a wall with friction is not available (frictionless only)")


def critical_step(omega_max: float) -> float:
    """Stability limit of undamped central differences, ``2 / omega_max`` (s)."""
    return 2.0 / omega_max


class ExplicitSystem:
    """Internal forces, material state and the wall of a model with a lumped mass, on the
    free dofs.

    Attributes
    ----------
    m : (n_free,) lumped mass
    sigma : (n_qp, nc) stress of the last state (Mandel, mesh frame)
    peps : (n_qp,) equivalent plastic strain
    """

    def __init__(self, model: Model):
        self.model = model
        free = model.free
        self.m = model.M.diagonal()[free]
        self.K = model.stiffness()[free][:, free].tocsr()
        self.law = model.law
        self.plastic = self.law.nonlinear  # else the stress is D eps: the linear path
        nc = forms.n_components(model.dim)
        self.state = self.law.initial_state(model.n_qp)
        self._sigma = np.zeros((model.n_qp, nc))
        self._u = np.zeros(free.size)
        self._sigma_of = None  # the u that _sigma belongs to, for elastic runs (computed lazily)
        self.wall = _Wall(model) if model.case.wall is not None else None
        self.pairs = _Pairs(model) if model.case.contacts else None

    @property
    def B(self):
        return self.model.free_B  # made when first read (plastic steps, stresses at every point)

    @functools.cached_property
    def BT(self):
        return self.B.T  # a CSC view: its product is faster than that of a CSR copy

    @property
    def sigma(self) -> np.ndarray:
        if not self.plastic and self._sigma_of is not self._u:
            self._sigma = forms.elastic_stress((self.B @ self._u).reshape(self.model.n_qp, -1), self.model.D)
            self._sigma_of = self._u
        return self._sigma

    def stress_at(self, q: int) -> np.ndarray:
        """The stress at quadrature point ``q``, ``(nc,)``: of its own strain rows only, for
        an elastic body (a probe must not cost a product over the whole mesh)."""
        if self.plastic:
            return self._sigma[q]
        return forms.at_points(self.model.D, q) @ (self.model.free_strain_rows(q) @ self._u)

    @property
    def peps(self) -> np.ndarray:
        return self.law.equivalent_plastic_strain(self.state)

    def internal_forces(self, u: np.ndarray) -> np.ndarray:
        """``f_int(u)`` (N); a plastic body commits the law's state (von Mises: the radial return's)."""
        self._u = u
        if not self.plastic:
            return self.K @ u
        model = self.model
        eps = (self.B @ u).reshape(model.n_qp, -1)
        self._sigma, self.state = self.law.stress(eps, self.state, tangent=False)
        return self.BT @ (self._sigma * model.weights[:, None]).ravel()

    def constrain(self, u_new: np.ndarray) -> np.ndarray:
        """The correction that puts the face nodes of ``u_new`` that went through the wall back
        on it, or the pairs' nodes that went through each other back to touching (zero without
        contact); the pairs' friction measures the slip from the last state, ``u_n``."""
        if self.pairs is not None:
            return self.pairs.correction(u_new, self._u)
        if self.wall is None:
            return np.zeros_like(u_new)
        return self.wall.correction(u_new)


class _Wall:
    """The rigid wall as a kinematic constraint on the face nodes' free dofs."""

    def __init__(self, model: Model):
        case = model.case  # (what the engine cannot take it refused before: refuse)
        face = plane_face(model, case.wall.edge)
        dim = model.dim
        where = np.full(model.basis.N, -1)
        where[model.free] = np.arange(model.free.size)
        cols = where[face.nodes[:, None] * dim + np.arange(dim)]  # (n_face, dim) free index or -1
        normal = np.where(np.abs(face.normal) > 1e-12, face.normal, 0.0)
        moving = normal != 0
        # a node can be pushed back along the normal only if every normal-direction dof is free
        ok = np.all((cols >= 0) | ~moving, axis=1)
        self.cols = cols[ok][:, moving]
        self.normal = normal[moving]
        self.g0 = initial_gaps(model, face, face.nodes[ok])
        self.n_nodes = int(ok.sum())

    def correction(self, u: np.ndarray) -> np.ndarray:
        du = np.zeros_like(u)
        gap = self.g0 - u[self.cols] @ self.normal  # the normal points from the body to the wall
        through = gap < 0
        if through.any():
            du[self.cols[through]] = gap[through, None] * self.normal
        return du


class _Pairs:
    """The contact pairs as a kinematic constraint on their matched nodes' free dofs (module doc)."""

    def __init__(self, model: Model):
        m = all_pairs(model)  # (the model refuses what pairs are not solved with: plasticity, ...)
        dim = model.dim
        nodes, others, self.normals, self.g0, self.friction = m.nodes, m.others, m.normals, m.g0, m.friction
        where = np.full(model.basis.N, -1)
        where[model.free] = np.arange(model.free.size)
        mass = model.M.diagonal()  # lumped: one per dof, alike for a node's components
        along = self.normals != 0
        self.cols, self.w = [], []
        for side in (nodes, others):
            cols = where[side[:, None] * dim + np.arange(dim)]  # (n, dim) free index or -1
            # a node moves along the normal only if every dof with a normal component is free
            movable = np.all((cols >= 0) | ~along, axis=1)
            self.cols.append(cols)
            self.w.append(np.where(movable, 1.0 / mass[side * dim], 0.0))  # its inverse mass
        self.w_sum = self.w[0] + self.w[1]
        if not np.any(self.w_sum > 0):
            raise UnsupportedCase("explicit reference: no node of a contact pair's faces can move along their normal")
        self.w_sum = np.where(self.w_sum > 0, self.w_sum, np.inf)  # both held: never corrected
        self.tangents = tangent_bases(self.normals) if np.any(self.friction > 0) else None
        self.n_nodes = int(nodes.size)
        self.n_pairs = len(model.case.contacts)

    def _at(self, u: np.ndarray, side: int) -> np.ndarray:
        cols = self.cols[side]
        return np.where(cols >= 0, u[cols], 0.0)

    def correction(self, u: np.ndarray, u_old: np.ndarray) -> np.ndarray:
        du = np.zeros_like(u)
        relative = self._at(u, 1) - self._at(u, 0)
        gap = self.g0 + np.einsum("nk,nk->n", self.normals, relative)
        closed = np.flatnonzero(gap < 0)
        if closed.size == 0:
            return du
        P = -gap[closed] / self.w_sum[closed]  # the normal impulse times dt
        push = self.normals[closed] * P[:, None]  # on the other node; minus it on the face's
        if self.tangents is not None:
            T = self.tangents[closed]
            moved = relative[closed] - (self._at(u_old, 1) - self._at(u_old, 0))[closed]
            slip = -np.einsum("nak,nk->na", T, moved)  # the face node's slip relative to the other
            tau = slip / self.w_sum[closed, None]
            size = np.linalg.norm(tau, axis=1)
            limit = self.friction[closed] * P
            tau *= np.where(size > limit, limit / np.where(size > 0, size, 1.0), 1.0)[:, None]
            push = push + np.einsum("nak,na->nk", T, tau)
        for side, sign in ((0, -1.0), (1, 1.0)):
            cols = self.cols[side][closed]
            on = cols >= 0
            np.add.at(du, cols[on], (sign * push * self.w[side][closed, None])[on])
        return du


def march(system: ExplicitSystem, Q, v0: np.ndarray, dt: float, n_steps: int
          ) -> Iterator[tuple[int, float, np.ndarray, np.ndarray, np.ndarray]]:
    """Yield ``(n, t_n, u_n, v_n, a_n)`` for n = 0 .. ``n_steps`` (free dofs; from rest in
    displacement, at velocity ``v0``). ``a_n`` includes the wall's force, known only once
    ``u_n+1`` is predicted, so step n is yielded after that prediction; at t = 0 it is the
    initial acceleration ``M a_0 = Q - f_int(u_0)`` (the initial state every solver reports:
    the wall's force acts from the first step on)."""
    u = np.zeros_like(v0)
    load = Q if callable(Q) else (lambda t: Q)
    for n in range(n_steps + 1):
        a = (load(n * dt) - system.internal_forces(u)) / system.m
        if n == 0:  # the first half step: u_1 = u_0 + dt v_0 + dt^2 / 2 a_0
            u_new = u + dt * v0 + 0.5 * dt * dt * a
            du = system.constrain(u_new)
            yield n, 0.0, u, v0, a
            v_half = v0 + 0.5 * dt * (a + 2.0 * du / (dt * dt))
        else:
            u_new = u + dt * (v_half + dt * a)
            du = system.constrain(u_new)
            a = a + du / (dt * dt)
            v = v_half + 0.5 * dt * a
            yield n, n * dt, u, v, a
            v_half = v + 0.5 * dt * a
        u = u_new + du


def _balance(system: ExplicitSystem, u: np.ndarray, v: np.ndarray, when: str) -> dict:
    """Kinetic plus strain energy and momentum per mesh component of the state ``u``, ``v``."""
    model = system.model
    factor = 2 * np.pi if model.rep == AXISYMMETRIC else 1.0
    p = np.zeros(model.basis.N)
    p[model.free] = system.m * v
    # elementwise products, not BLAS dot (its threads stall on a busy machine)
    energy = 0.5 * factor * float(np.sum(v * system.m * v) + np.sum(u * (system.K @ u)))
    return {f"energy_{when}": energy, f"momentum_{when}": (factor * p.reshape(-1, model.dim).sum(axis=0)).tolist()}


def output_steps(t_out: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """For each output time, the step at or before it and its weight toward the next step:
    ``t = (n + theta) dt`` with ``0 <= theta < 1`` (round-off of a time on a step is a step)."""
    x = t_out / dt
    n = np.floor(x + 1e-9).astype(int)
    return n, np.clip(x - n, 0.0, None)


def solve(case, progress: Callable[[int, int], None] | None = None, every: int = 0,
          grading: float = 1.0, bbar: bool = False, step_divisor: int = 1, fields: bool = True) -> RunResult:
    """The case's probe histories at ``t = 0, dt, ..., t_end`` by central differences.

    The step is :data:`SAFETY` times the critical step (over ``step_divisor``), the same
    fraction on every mesh, so that the time error shrinks with the mesh: ``case.dt`` is the
    output interval only, and a probe's value at an output time is interpolated linearly
    between the two steps around it.

    Parameters
    ----------
    case : cases.Case (2D or 3D as its ``dim`` says)
    progress : optional ``callable(step, n_steps)`` per output time
    every : also the field every ``every`` output times (``frames``, at the step at or before
        each; 0: none)
    grading : mesh grading toward the re-entrant corner lines (:func:`reference_fem.mesh.build_mesh`)
    bbar : the strain operator's volumetric part projected per element (:func:`reference_fem.forms.bbar_operator`)
    step_divisor : a further division of the step, for measuring the time error
    fields : the final state as ``mesh`` (:func:`reference_fem.solver.solve`'s; False: None)

    Returns
    -------
    cases.result.RunResult; ``iterations`` 1 per output time; ``info``: ``'method'``,
    ``'omega_max'`` (rad/s), ``'critical_step'``, ``'time_step'`` (s), ``'steps'``,
    ``'safety'``, ``'grading'``, ``'bbar'``, the mesh's ``'counts'`` and ``'n_elements'``,
    ``'cpu_mesh_s'``; with a wall ``'contact_nodes'``; with contact pairs ``'contact_nodes'``,
    ``'contact_pairs'`` and the kinetic plus strain energy (J) and the momentum ``m v`` summed
    per mesh component (kg m/s) at t = 0 and at the last step, ``'energy_before'``,
    ``'energy_after'``, ``'momentum_before'``, ``'momentum_after'`` (times 2 pi when
    axisymmetric, as the implicit reference's, :mod:`reference_fem.pairs`).
    """
    from .solver import load_history, output_mesh

    if step_divisor < 1:
        raise ValueError("step_divisor must be a positive integer")
    refuse(case)
    cpu0 = time.process_time()
    rmesh = build_mesh(case, grading)
    cpu_mesh = time.process_time() - cpu0
    cpu1 = time.process_time()
    model = Model(case, rmesh, lumped=True, bbar=bbar)
    system = ExplicitSystem(model)
    omega_max = largest_frequency(system.K, system.m)
    dt_cr = critical_step(omega_max)
    dt = SAFETY * dt_cr / step_divisor
    n_out = case.n_steps
    t_out = np.arange(n_out + 1) * case.dt
    before, theta = output_steps(t_out, dt)
    wanted = set(before.tolist()) | set((before[theta > 0] + 1).tolist())
    probes = Probes(model)
    free = model.free
    u_full, v_full, a_full = (np.zeros(model.basis.N) for _ in range(3))
    v0 = model.initial_velocity()[free]
    values, frames, j = {}, [], 0
    for n, t, u, v, a in march(system, load_history(model), v0, dt, int(before[-1] + (theta[-1] > 0))):
        if n not in wanted:
            continue
        if not (np.isfinite(u).all() and np.isfinite(v).all()):
            raise FloatingPointError(f"explicit reference: non-finite state at t = {t:.6g} s (unstable)")
        u_full[free], v_full[free], a_full[free] = u, v, a
        values[n] = np.array(probes.values(u_full, system, v_full, a_full))
        while j <= n_out and before[j] <= n:
            if every and j % every == 0:
                frames.append((t_out[j], output_mesh(model, u_full, system, v_full)))
            if progress is not None:
                progress(j, n_out)
            j += 1
    rows = np.array([values[b] if w == 0 else (1 - w) * values[b] + w * values[b + 1]
                     for b, w in zip(before, theta)])
    cpu = time.process_time() - cpu1
    info = {"method": "central differences, HRZ-lumped mass", "omega_max": omega_max, "critical_step": dt_cr,
            "time_step": dt, "steps": int(before[-1] + (theta[-1] > 0)), "safety": SAFETY / step_divisor,
            "grading": grading, "bbar": bbar, "dim": model.dim, "representation": model.rep,
            "element": type(model.element.elem).__name__, "n_elements": int(rmesh.mesh.nelements),
            "intorder": INTORDER, "counts": rmesh.counts, "cpu_mesh_s": cpu_mesh}
    if system.wall is not None:
        info["contact_nodes"] = system.wall.n_nodes
    if system.pairs is not None:
        u, v = u_full[free], v_full[free]
        info.update(contact_nodes=system.pairs.n_nodes, contact_pairs=system.pairs.n_pairs,
                    **_balance(system, np.zeros_like(v0), v0, "before"), **_balance(system, u, v, "after"))
    return RunResult(t=t_out, history=dict(zip(probes.names, rows.T)), n_dof=int(free.size),
                     iterations=[1] * n_out, converged=True, message="", cpu_time_s=cpu,
                     mesh=output_mesh(model, u_full, system, v_full) if fields else None, frames=frames,
                     info=info)
