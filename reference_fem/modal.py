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

A load that varies in time, ``Q_k f_k(t)`` (:class:`~reference_fem.harmonic.LoadTerm`), drives
each mode by ``y'' + omega^2 y = f_k``. Over a piece where ``f_k`` is linear the solution is
closed-form (:func:`modal_coordinates`), so a piecewise-linear amplitude is integrated exactly
(breakpoints: its points and the output times). A moving patch's ``f_k`` is smooth between
its kinks but not linear: it is sampled, linear between samples ``rate h <= PHASE_STEP`` apart,
and the error of that sampling measured by halving the samples (:class:`ModalResult`).

:func:`newmark_histories` integrates the same matrices with Newmark's method, for the check
that Newmark converges to the modal response (order 2 in dt).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as la
import scipy.sparse.linalg as sla

from cases.result import RunResult

from .harmonic import HarmonicModel, LoadTerm
from .linalg import factorize
from .newmark import march, newmark_constants

#: the largest harmonic decomposed whole (dense eigenproblem)
MAX_DENSE = 3000
#: modes kept of a larger harmonic (mode acceleration)
PARTIAL_MODES = 400
#: the largest phase ``rate h`` (rad) between a moving load's samples: a chord through samples
#: this close misses a sinusoid by at most ``(rate h)^2 / 8`` = 2e-6 of its amplitude (the moving
#: strip at its defaults: sampling error measured 6.1e-6, three times the actual 2.0e-6; 0.02
#: gave 5.6e-5, 0.002 1.5e-6 at 1.3 times the CPU)
PHASE_STEP = 0.004
#: elements of one (modes, pieces) block of :func:`modal_coordinates` (memory, not accuracy)
BLOCK = 1 << 21


@dataclass
class TermModes:
    """A timed load's modal data: ``coef[p, i] = (P phi_i)_p (phi_i . Q_k)`` and, for a
    truncated basis, ``static[p] = (P K^-1 Q_k)_p``."""

    term: LoadTerm
    coef: np.ndarray
    static: np.ndarray | None


@dataclass
class Modes:
    """The modal data of one harmonic that the probes need.

    ``omega`` (rad/s, >= 0), ``coef[p, i] = (P phi_i)_p (phi_i . Q)`` and, for a truncated
    basis, ``static[p] = (P K^-1 Q)_p`` (``None`` when every mode is kept), of the load held
    from t = 0; ``terms``: the same per load that varies in time (:class:`TermModes`).
    """

    omega: np.ndarray
    coef: np.ndarray
    static: np.ndarray | None
    terms: list[TermModes] = field(default_factory=list)


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
    shapes = h.P @ phi
    lu = factorize(h.K) if static is not None and h.terms else None
    terms = [TermModes(term, shapes * (phi.T @ term.Q), None if lu is None else h.P @ lu.solve(term.Q))
             for term in h.terms]
    return Modes(np.sqrt(w2), shapes * (phi.T @ h.Q), static, terms)


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


# -- loads that vary in time ---------------------------------------------------------------
@dataclass
class Samples:
    """Where a timed load's factor is looked at: ``tau`` (increasing, ``tau[0] = 0``), cut into
    pieces between breakpoints, piece ``j`` into ``steps[j]`` equal sub-steps; ``out``: the
    indices of the output times in ``tau``."""

    tau: np.ndarray
    steps: np.ndarray
    out: np.ndarray


def timeline(term: LoadTerm, t: np.ndarray, phase_step: float = PHASE_STEP, halve: bool = False) -> Samples:
    """The samples of ``term``'s factor over ``[0, t[-1]]``.

    The breakpoints are 0, the output times ``t`` and the term's kinks (one within round-off of
    an output time is that time). A piecewise-linear factor (``rate`` 0) needs no more; a smooth
    one has each piece cut into an even number of equal sub-steps with ``rate h <= phase_step``,
    or into half as many (``halve``: every other sample of the full count, to measure the
    sampling error).
    """
    t = np.asarray(t, float)
    near = 1e-12 * t[-1]
    kinks = [x for x in term.kinks if near < x < t[-1] and np.abs(t - x).min() > near]
    base = np.union1d(np.union1d([0.0], t), kinks)
    h = np.diff(base)
    steps = np.ones(h.size, int)
    if term.rate > 0.0:
        steps = np.maximum(1, np.ceil(term.rate * h / (2 * phase_step))).astype(int) * (1 if halve else 2)
    piece = np.repeat(np.arange(h.size), steps)
    k = np.arange(piece.size) - np.repeat(np.cumsum(steps) - steps, steps)
    tau = np.append(base[piece] + h[piece] * (k / steps[piece]), base[-1])  # k = 0: the breakpoint itself
    return Samples(tau, steps, np.searchsorted(tau, t))


def _ramp_weights(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``A = int_0^1 x e^(i theta x) dx`` and ``B = int_0^1 (1 - x) e^(i theta x) dx``: the
    weights of a linear piece's start and end values (a series where the closed form cancels)."""
    small = np.abs(theta) < 1.0
    safe = np.where(small, 1.0, theta)
    E = np.exp(1j * safe)
    A = (E - 1.0 - 1j * safe * E) / safe**2
    B = (E - 1.0) / (1j * safe) - A
    x = 1j * theta[small]
    a, b, power = np.zeros_like(x), np.zeros_like(x), np.ones_like(x)
    for n in range(20):  # |theta| < 1: the 20th term is below 1e-18
        a += power / (n + 2)
        b += power / ((n + 1) * (n + 2))
        power = power * x / (n + 1)
    A[small], B[small] = a, b
    return A, B


def _piece_gains(w: np.ndarray, tau: np.ndarray, f: np.ndarray, first: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """``(n_pieces, n_modes)``: what ``z = y' + i w y`` gains across each piece from ``z = 0``,
    ``sum_k r^(m-1-k) hs (A f_k + B f_(k+1))`` over its ``m`` sub-steps ``hs`` (``r = e^(i w hs)``).
    Pieces of one length and count share their weights: a matrix product each."""
    H = tau[first[1:]] - tau[first[:-1]]
    keys, group = np.unique(np.column_stack([H, steps]), axis=0, return_inverse=True)
    gains = np.empty((steps.size, w.size), complex)
    for g, (length, m) in enumerate(keys):
        m = int(m)
        hs = length / m
        pieces = np.flatnonzero(group.ravel() == g)
        A, B = _ramp_weights(w * hs)
        R = np.exp(1j * np.outer(hs * np.arange(m - 1, -1, -1), w))
        k = first[pieces][:, None] + np.arange(m)[None, :]
        weights, values = np.vstack([R * A, R * B]), np.hstack([f[k], f[k + 1]])
        # real products: numpy's complex-by-real product does not use BLAS (ten times slower)
        gains[pieces] = hs * (values @ weights.real + 1j * (values @ weights.imag))
    return gains


def modal_coordinates(omega: np.ndarray, tau: np.ndarray, f: np.ndarray, out: np.ndarray,
                      steps: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Exact ``y`` and ``y'`` at ``tau[out]`` of ``y'' + omega^2 y = f(s)`` from rest at
    ``tau[0] = 0``, ``f`` linear between the samples ``(tau, f)``; each ``(n_modes, len(out))``.

    With ``z = y' + i omega y``, ``z' = i omega z + f``: across a linear piece of length ``h``
    the rotation ``z -> e^(i omega h) z`` plus ``h (A f_j + B f_(j+1))`` (:func:`_ramp_weights`),
    the particular part of ``a + b s``. ``steps`` (default: one per interval) groups the samples
    into pieces of equal sub-steps (:class:`Samples`), whose gains are summed first
    (:func:`_piece_gains`); then, unrolled over pieces, ``z(T_n) = e^(i omega T_n) sum_(j<n)
    gain_j e^(-i omega T_(j+1))``, a cumulative sum in blocks. The output times must be piece
    ends. A rigid mode (omega = 0) integrates ``f`` twice, exactly for a linear ``f``.
    """
    steps = np.ones(tau.size - 1, int) if steps is None else np.asarray(steps)
    first = np.concatenate([[0], np.cumsum(steps)])  # sample index of each piece end
    node = np.searchsorted(first, out)
    if np.any(first[np.minimum(node, first.size - 1)] != out):
        raise ValueError("the output times must be ends of pieces")
    T = tau[first]
    y, yd = np.zeros((out.size, omega.size)), np.zeros((out.size, omega.size))  # time-major: rows contiguous
    elastic = omega > 0.0
    w = omega[elastic]
    if w.size:
        gains = _piece_gains(w, tau, f, first, steps)
        ends = np.zeros((steps.size + 1, w.size), complex)  # z at every piece end
        # e^(-i w T) at the piece ends by products of each length's turn (exact differences of the
        # ends), from an exact exponential at each block's start: k products err by ~k eps
        lengths, which = np.unique(np.diff(T), return_inverse=True)
        turns = np.exp(-1j * np.outer(lengths, w))
        carry = np.zeros(w.size, complex)
        width = max(1, BLOCK // w.size)
        for j0 in range(0, steps.size, width):
            j1 = min(j0 + width, steps.size)
            back = turns[which.ravel()[j0:j1]]
            back[0] = np.exp(-1j * w * T[j0 + 1])
            np.cumprod(back, axis=0, out=back)
            part = np.multiply(gains[j0:j1], back, out=ends[j0 + 1:j1 + 1])
            np.cumsum(part, axis=0, out=part)
            part += carry
            carry = part[-1].copy()
            part *= np.conjugate(back, out=back)
        z = ends[node]
        y[:, elastic], yd[:, elastic] = z.imag / w, z.real
    if not elastic.all():
        h = np.diff(tau)
        v = np.concatenate([[0.0], np.cumsum(h * (f[:-1] + f[1:]) / 2)])
        x = np.concatenate([[0.0], np.cumsum(h * v[:-1] + h * h * (f[:-1] / 3 + f[1:] / 6))])
        y[:, ~elastic], yd[:, ~elastic] = x[out, None], v[out, None]
    return y.T, yd.T


@dataclass
class Coordinates:
    """A timed load's unit modal response at the output times: ``y``, ``yd`` (modes, n_t) and
    its factor ``f`` and slope ``df`` there (the mean of the two sides at a kink)."""

    y: np.ndarray
    yd: np.ndarray
    f: np.ndarray
    df: np.ndarray


def term_coordinates(omega: np.ndarray, term: LoadTerm, t: np.ndarray, phase_step: float = PHASE_STEP,
                     halve: bool = False) -> Coordinates:
    """Every mode's response to ``term``'s factor at ``t`` (:func:`timeline`, :func:`modal_coordinates`)."""
    samples = timeline(term, t, phase_step, halve)
    tau, out = samples.tau, samples.out
    f = np.asarray(term.factor(tau), float)
    y, yd = modal_coordinates(omega, tau, f, out, samples.steps)
    slope = np.diff(f) / np.diff(tau)
    left = np.concatenate([[np.nan], slope])[out]
    right = np.concatenate([slope, [np.nan]])[out]
    df = np.where(np.isnan(left), right, np.where(np.isnan(right), left, (left + right) / 2))
    return Coordinates(y, yd, f[out], np.nan_to_num(df))


def term_response(m: Modes, tm: TermModes, c: Coordinates, keep: int | None = None):
    """Probe displacement and velocity ``(n_probes, n_t)`` of one timed load from its
    coordinates; with a truncated basis, the modes left out answer statically (mode
    acceleration: ``u = static f + sum coef (y - f / omega^2)``, and ``v`` likewise with
    ``y'`` and ``f'``). ``keep``: only the ``keep`` lowest modes."""
    n = m.omega.size if keep is None else keep
    coef, w = tm.coef[:, :n], m.omega[:n]
    if tm.static is None:
        return coef @ c.y[:n], coef @ c.yd[:n]
    inv = np.where(w > 0.0, 1.0 / np.where(w > 0.0, w, 1.0) ** 2, 0.0)[:, None]
    u = np.outer(tm.static, c.f) + coef @ (c.y[:n] - inv * c.f)
    v = np.outer(tm.static, c.df) + coef @ (c.yd[:n] - inv * c.df)
    return u, v


@dataclass
class ModalResult:
    """Probe histories of a modal run and how exact they are.

    ``truncation[probe]``: relative max-norm change when the truncated harmonics keep half
    their modes (0 when every harmonic was decomposed whole). ``sampling[probe]``: relative
    max-norm change when the loads sampled between their kinks (moving patches) have half their
    samples (0 when every load is piecewise linear in time, so exact).
    """

    t: np.ndarray
    history: dict
    truncation: dict
    n_dof: int
    modes: int
    sampling: dict = field(default_factory=dict)


def histories(model, t: np.ndarray, phase_step: float = PHASE_STEP) -> ModalResult:
    """Exact probe histories of ``model`` (:class:`~reference_fem.harmonic.HarmonicModel`) at
    ``t`` (increasing, from 0); a moving load's factor sampled ``phase_step`` apart (:func:`timeline`)."""
    t = np.asarray(t, float)
    n_p = len(model.probes)
    total, half, coarse = (np.zeros((n_p, t.size)) for _ in range(3))
    modes = 0
    is_v = np.array([f == "v" for f in model.fields])[:, None]
    for h in model.systems:
        m = modes_of(h)
        truncated = m.static is not None
        if np.any(h.Q):
            u, v = probe_response(m, t)
            total += np.where(is_v, v, u)
            coarse += np.where(is_v, v, u)
            u2, v2 = probe_response(m, t, keep=m.omega.size // 2) if truncated else (u, v)
            half += np.where(is_v, v2, u2)
        for tm in m.terms:
            c = term_coordinates(m.omega, tm.term, t, phase_step)
            u, v = term_response(m, tm, c)
            total += np.where(is_v, v, u)
            u2, v2 = term_response(m, tm, c, keep=m.omega.size // 2) if truncated else (u, v)
            half += np.where(is_v, v2, u2)
            if tm.term.rate > 0.0:
                u, v = term_response(m, tm, term_coordinates(m.omega, tm.term, t, phase_step, halve=True))
            coarse += np.where(is_v, v, u)
        modes += m.omega.size
    return ModalResult(t, dict(zip(model.probes, total)), _relative(model.probes, total, half), model.n_dof, modes,
                       _relative(model.probes, total, coarse))


def _relative(probes, total: np.ndarray, other: np.ndarray) -> dict:
    """Per probe, ``max |total - other| / max |total|`` (0 for a probe that stays at 0)."""
    out = {}
    for k, name in enumerate(probes):
        scale = np.abs(total[k]).max()
        out[name] = float(np.abs(total[k] - other[k]).max() / scale) if scale else 0.0
    return out


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
    ``t = 0, dt, ..., n_steps dt``; a harmonic's load ``Q(t)`` taken at each step."""
    a0 = newmark_constants(dt).a0
    out = np.zeros((len(model.probes), n_steps + 1))
    is_v = np.array([f == "v" for f in model.fields])
    for h in model.systems:
        system = _Linear(h.K, h.M, a0)
        zero = np.zeros(h.K.shape[0])
        for n, _, u, v, _, _ in march(system, h.load if h.terms else h.Q, zero, zero, dt, n_steps):
            out[:, n] += np.where(is_v, h.P @ v, h.P @ u)
    return dict(zip(model.probes, out))


def solve(case, progress=None):
    """The case's probe histories at ``t = 0, dt, ..., t_end``, exact in time.

    Returns a :class:`cases.result.RunResult` with no time steps
    (``iterations`` empty: ``dt`` only sets where the histories are sampled) and ``info``:
    ``'method'``, ``'harmonics_used'``, ``'modes'`` (modes summed over all harmonics),
    ``'truncation'`` and ``'load_sampling'`` (per probe, see :class:`ModalResult`).

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
              "truncation": result.truncation, "load_sampling": result.sampling,
              "n_elements": int(model.mesh.nelements)},
    )
