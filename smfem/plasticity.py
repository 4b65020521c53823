"""von Mises plasticity with linear isotropic hardening: Wilkins' correction (paper (16)).

Pure, vectorised over any number of points. Stresses are Voigt ``[s11, s22, s33, s12, s13, s23]``
(tensor shear components); ``T = sqrt(S:S / 2)`` is the intensity of shear stresses and the
yield condition ``T <= tau_s``, i.e. ``sqrt(3) T <= sigma_y`` (von Mises). With hardening the
yield stress grows with the equivalent plastic strain ``peps = int sqrt(2/3 d eps_p : d eps_p)``:
``sigma_y = sigma_y0 + H peps``. The correction scales the trial deviator back to the yield
surface (radial return), which for ideal plasticity is exactly Wilkins' formula
``sigma = sigma_0 I + S tau_s / T``.

Two plastic measures are tracked: the accumulated ``alpha = int sqrt(2/3 d eps_p : d eps_p)``,
which drives hardening and never decreases, and the plastic strain tensor ``eps_p`` (Voigt,
engineering shears), whose intensity ``sqrt(2/3 eps_p : eps_p)`` is what probes report as
``peps`` (docs/scenes.md); it can fall under reversed flow.
"""

from __future__ import annotations

import math

import numpy as np

SQRT3 = math.sqrt(3.0)


def shear_intensity(sigma: np.ndarray) -> np.ndarray:
    """``T = sqrt(S:S / 2)`` of Voigt stresses (..., 6)."""
    return np.sqrt(_shear_squared(np.moveaxis(sigma, -1, 0)))


def von_mises(rows: np.ndarray) -> np.ndarray:
    """``sqrt(3) T`` of stresses stored rows first, (6, ...)."""
    return SQRT3 * np.sqrt(_shear_squared(rows))


def _shear_squared(rows: np.ndarray) -> np.ndarray:
    """``T^2`` of stresses stored rows first, (6, ...)."""
    mean = (rows[0] + rows[1] + rows[2]) / 3.0
    return 0.5 * ((rows[0] - mean) ** 2 + (rows[1] - mean) ** 2 + (rows[2] - mean) ** 2) \
        + rows[3] ** 2 + rows[4] ** 2 + rows[5] ** 2


def _radial_return(trial: np.ndarray, eq: np.ndarray, alpha: np.ndarray, mu: np.ndarray, sigma_y0: float, H: float):
    """The return of yielding trial stresses (6, n) with von Mises stress ``eq = sqrt(3) T``
    above the yield stress: ``sigma, alpha, d_eps_p`` (engineering shears)."""
    dalpha = (eq - (sigma_y0 + H * alpha)) / (3 * mu + H)
    scale = 1.0 - 3 * mu * dalpha / eq
    sigma = trial * scale
    sigma[:3] += (trial[0] + trial[1] + trial[2]) / 3.0 * (1.0 - scale)  # the mean stress is left alone
    # the deviator lost is 2 mu d_eps_p (tensor components; shears doubled for engineering)
    deps_p = (trial - sigma) / (2 * mu)
    deps_p[3:] *= 2.0
    return sigma, alpha + dalpha, deps_p


def wilkins(trial: np.ndarray, alpha: np.ndarray, mu: np.ndarray, sigma_y0: float, H: float):
    """Return-map trial stresses onto the yield surface.

    Parameters
    ----------
    trial : (..., 6) trial stresses ``sigma_n + D d_eps``
    alpha : (...) accumulated equivalent plastic strain at the start of the step
    mu : (...) shear modulus at each point (the contrast material's is scaled)
    sigma_y0, H : initial yield stress in tension and the plastic modulus: numbers, or per
        point (n,) arrays in :func:`return_map_rows`

    Returns
    -------
    sigma : (..., 6), alpha : (...), d_eps_p : (..., 6) plastic strain increment (engineering
    shears), yielding : (...) bool
    """
    shape = trial.shape[:-1]
    rows = np.moveaxis(trial, -1, 0).reshape(6, -1)
    sigma, alpha_new, at, deps = return_map_rows(rows, np.broadcast_to(alpha, shape).ravel(),
                                                 np.broadcast_to(mu, shape).ravel(), sigma_y0, H)
    deps_p = np.zeros_like(rows)
    deps_p[:, at] = deps
    yielding = np.zeros(rows.shape[1], bool)
    yielding[at] = True
    back = lambda r: np.moveaxis(r.reshape((6,) + shape), 0, -1)
    return back(sigma), alpha_new.reshape(shape), back(deps_p), yielding.reshape(shape)


def yield_stress(alpha: np.ndarray, sigma_y0, H):
    """The yield stress in von Mises' measure after hardening ``alpha`` (n,): ``sigma_y0 + H alpha``,
    or ``sigma_y0`` as it is (a scalar, or one per point) where no point hardens: the law's
    hot path then squares no array of equal values."""
    return sigma_y0 + H * alpha if np.any(H) else sigma_y0


def return_map_rows(trial: np.ndarray, alpha: np.ndarray, mu: np.ndarray, sigma_y0: float, H: float):
    """Wilkins' correction of stresses stored rows first, ``(6, n)``, at the points that yield
    only: the yield test is a few operations per point, the return runs on the few that yield.

    Returns ``sigma (6, n)`` (``trial`` itself if no point yields), ``alpha (n,)``, the indices
    of the yielding points and their plastic strain increments ``(6, n_yielding)``.
    """
    T2 = _shear_squared(trial)
    limit = yield_stress(alpha, sigma_y0, H)
    at = np.flatnonzero(3.0 * T2 > limit * limit)
    if not len(at):
        return trial, alpha, at, np.zeros((6, 0))
    # per-point constants (a section of several materials) at the yielding points only
    sigma_y0, H = (v if np.ndim(v) == 0 else v[at] for v in (sigma_y0, H))
    # np.take gathers into rows that are each contiguous (``trial[:, at]`` does not: the return's
    # arithmetic on them ran at half the speed)
    yielding = np.take(trial, at, axis=1)
    s, a, deps_p = _radial_return(yielding, SQRT3 * np.sqrt(T2[at]), alpha[at], mu[at], sigma_y0, H)
    sigma, alpha = trial.copy(), alpha.copy()
    sigma[:, at], alpha[at] = s, a
    return sigma, alpha, at, deps_p


def intensity(eps_p: np.ndarray) -> np.ndarray:
    """``sqrt(2/3 eps_p : eps_p)`` of Voigt strains with engineering shears (..., 6)."""
    return np.sqrt(2.0 / 3.0 * ((eps_p[..., :3] ** 2).sum(-1) + 0.5 * (eps_p[..., 3:] ** 2).sum(-1)))

