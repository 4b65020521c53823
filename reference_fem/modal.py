"""Exact time response of a :class:`~reference_fem.harmonic.HarmonicModel` by modal superposition.

Each harmonic ``M a + K u = Q H(t)`` (load on at t = 0, start from rest) is diagonalised by the
M-orthonormal modes ``phi_i`` of ``K phi = omega^2 M phi``:

    u(t) = sum_i phi_i (phi_i . Q) / omega_i^2 (1 - cos omega_i t)
    v(t) = sum_i phi_i (phi_i . Q) / omega_i sin omega_i t

and a rigid mode (omega = 0) contributes ``phi (phi . Q) t^2 / 2``. There is no time step, so
no time error: what remains is the spatial error of the model. A harmonic small enough is
decomposed whole (dense); a larger one keeps its ``n_modes`` lowest modes and adds the static
response of the rest (the mode-acceleration method,
``u = K^-1 Q - sum_i phi_i (phi_i . Q) / omega_i^2 cos omega_i t``), whose truncation error
:func:`histories` measures by halving ``n_modes``.

:func:`newmark_histories` integrates the same matrices with Newmark's method, for the check
that Newmark converges to the modal response (order 2 in dt).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as la
import scipy.sparse.linalg as sla

from cases.result import RunResult

from .harmonic import HarmonicModel
from .linalg import factorize
from .newmark import march, newmark_constants

#: the largest harmonic decomposed whole (dense eigenproblem)
MAX_DENSE = 3000
#: modes kept of a larger harmonic (mode acceleration)
PARTIAL_MODES = 400


@dataclass
class Modes:
    """The modal data of one harmonic that the probes need.

    ``omega`` (rad/s, >= 0), ``coef[p, i] = (P phi_i)_p (phi_i . Q)`` and, for a truncated
    basis, ``static[p] = (P K^-1 Q)_p`` (``None`` when every mode is kept).
    """

    omega: np.ndarray
    coef: np.ndarray
    static: np.ndarray | None


def modes_of(h, n_modes: int | None = None) -> Modes:
    """Modal data of harmonic ``h`` (:class:`~reference_fem.harmonic.Harmonic`)."""
    n = h.K.shape[0]
    if n <= MAX_DENSE and n_modes is None:
        w2, phi = la.eigh(h.K.toarray(), h.M.toarray())
        static = None
    else:
        k = min(n_modes or PARTIAL_MODES, n - 2)
        w2, phi = sla.eigsh(h.K.tocsc(), k=k, M=h.M.tocsc(), sigma=0.0, which="LM")
        static = h.P @ sla.spsolve(h.K.tocsc(), h.Q)
    w2 = np.where(w2 < 1e-12 * np.abs(w2).max(), 0.0, w2)
    return Modes(np.sqrt(w2), (h.P @ phi) * (phi.T @ h.Q), static)


def probe_response(m: Modes, t: np.ndarray, keep: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Displacement and velocity of the probes, each ``(n_probes, n_t)``, at times ``t``.

    ``keep``: use only the ``keep`` lowest modes (of a truncated basis), to measure truncation.
    """
    omega, coef = (m.omega, m.coef) if keep is None else (m.omega[:keep], m.coef[:, :keep])
    rigid = omega == 0.0
    wt = np.outer(omega, t)
    safe = np.where(rigid, 1.0, omega)
    c_el = np.where(rigid, 0.0, 1.0 / safe**2) * coef
    u = -c_el @ np.cos(wt) + np.outer(coef[:, rigid].sum(axis=1), 0.5 * t * t)
    u += m.static[:, None] if m.static is not None else c_el.sum(axis=1)[:, None]
    v = (c_el * omega) @ np.sin(wt) + np.outer(coef[:, rigid].sum(axis=1), t)
    return u, v


@dataclass
class ModalResult:
    """Probe histories of a modal run and how exact they are.

    ``truncation[probe]``: relative max-norm change when the truncated harmonics keep half
    their modes (0 when every harmonic was decomposed whole).
    """

    t: np.ndarray
    history: dict
    truncation: dict
    n_dof: int
    modes: int


def histories(model, t: np.ndarray) -> ModalResult:
    """Exact probe histories of ``model`` (:class:`~reference_fem.harmonic.HarmonicModel`)."""
    n_p = len(model.probes)
    total = np.zeros((n_p, t.size))
    half = np.zeros((n_p, t.size))
    modes = 0
    is_v = np.array([f == "v" for f in model.fields])
    for h in model.systems:
        m = modes_of(h)
        u, v = probe_response(m, t)
        total += np.where(is_v[:, None], v, u)
        modes += m.omega.size
        if m.static is not None:
            u2, v2 = probe_response(m, t, keep=m.omega.size // 2)
            half += np.where(is_v[:, None], v2, u2)
        else:
            half += np.where(is_v[:, None], v, u)
    truncation = {}
    for k, name in enumerate(model.probes):
        scale = np.abs(total[k]).max()
        truncation[name] = float(np.abs(total[k] - half[k]).max() / scale) if scale else 0.0
    return ModalResult(t, dict(zip(model.probes, total)), truncation, model.n_dof, modes)


class _Linear:
    """``(K + c M) u = rhs`` for :func:`~reference_fem.newmark.march`, factorized once."""

    def __init__(self, K, M, c: float):
        self.c, self.M = c, M
        self.A = (K + c * M).tocsc()
        self.lu = factorize(self.A)

    def solve(self, rhs, u):
        return self.lu.solve(rhs), 1


def newmark_histories(model, dt: float, n_steps: int) -> dict:
    """Probe histories of the same matrices by Newmark (alpha 0.25, delta 0.5), at
    ``t = 0, dt, ..., n_steps dt``."""
    a0 = newmark_constants(dt).a0
    out = np.zeros((len(model.probes), n_steps + 1))
    is_v = np.array([f == "v" for f in model.fields])
    for h in model.systems:
        system = _Linear(h.K, h.M, a0)
        zero = np.zeros(h.K.shape[0])
        for n, _, u, v, _, _ in march(system, h.Q, zero, zero, dt, n_steps):
            out[:, n] += np.where(is_v, h.P @ v, h.P @ u)
    return dict(zip(model.probes, out))


def solve(case, progress=None):
    """The case's probe histories at ``t = 0, dt, ..., t_end``, exact in time.

    Returns a :class:`cases.result.RunResult` with no time steps
    (``iterations`` empty: ``dt`` only sets where the histories are sampled) and ``info``:
    ``'method'``, ``'harmonics_used'``, ``'modes'`` (modes summed over all harmonics) and
    ``'truncation'`` (per probe, see :class:`ModalResult`).

    Raises
    ------
    cases.params.UnsupportedCase
        for a case without a harmonic model (see :func:`~reference_fem.harmonic.unsupported_reason`).
    """
    cpu0 = time.process_time()
    model = HarmonicModel(case)
    t = np.arange(case.n_steps + 1) * case.dt
    result = histories(model, t)
    if progress is not None:
        progress(case.n_steps, case.n_steps)
    return RunResult(
        t=t, history=result.history, n_dof=model.n_dof, iterations=[], converged=True, message="",
        cpu_time_s=time.process_time() - cpu0, mesh=None,
        info={"method": "modal superposition per harmonic (exact in time)",
              "harmonics_used": [h.l for h in model.systems], "modes": result.modes,
              "truncation": result.truncation, "n_elements": int(model.mesh.nelements)},
    )
