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
    s = sigma[..., :3] - sigma[..., :3].mean(axis=-1, keepdims=True)
    return np.sqrt(0.5 * (s * s).sum(-1) + (sigma[..., 3:] ** 2).sum(-1))


def wilkins(trial: np.ndarray, alpha: np.ndarray, mu: np.ndarray, sigma_y0: float, H: float):
    """Return-map trial stresses onto the yield surface.

    Parameters
    ----------
    trial : (..., 6) trial stresses ``sigma_n + D d_eps``
    alpha : (...) accumulated equivalent plastic strain at the start of the step
    mu : (...) shear modulus at each point (the contrast material's is scaled)
    sigma_y0, H : initial yield stress in tension and the plastic modulus

    Returns
    -------
    sigma : (..., 6), alpha : (...), d_eps_p : (..., 6) plastic strain increment (engineering
    shears), yielding : (...) bool
    """
    T = shear_intensity(trial)
    sigma_y = sigma_y0 + H * alpha
    yielding = SQRT3 * T > sigma_y
    if not yielding.any():
        return trial, alpha, np.zeros_like(trial), yielding
    eq = SQRT3 * T
    dalpha = np.where(yielding, (eq - sigma_y) / (3 * mu + H), 0.0)
    scale = np.where(yielding, 1.0 - 3 * mu * dalpha / np.where(yielding, eq, 1.0), 1.0)
    mean = trial[..., :3].mean(axis=-1, keepdims=True)
    sigma = trial * scale[..., None]
    sigma[..., :3] += mean * (1.0 - scale[..., None])  # the mean stress is left alone
    # the deviator lost is 2 mu d_eps_p (tensor components; shears doubled for engineering)
    deps_p = (trial - sigma) / (2 * np.where(yielding, mu, 1.0))[..., None]
    deps_p[..., 3:] *= 2.0
    return sigma, alpha + dalpha, deps_p, yielding


def intensity(eps_p: np.ndarray) -> np.ndarray:
    """``sqrt(2/3 eps_p : eps_p)`` of Voigt strains with engineering shears (..., 6)."""
    return np.sqrt(2.0 / 3.0 * ((eps_p[..., :3] ** 2).sum(-1) + 0.5 * (eps_p[..., 3:] ** 2).sum(-1)))
