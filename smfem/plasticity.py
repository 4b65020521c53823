"""von Mises plasticity with linear isotropic hardening: Wilkins' correction (paper (16)).

Pure, vectorised over any number of points. Stresses are Voigt ``[s11, s22, s33, s12, s13, s23]``
(tensor shear components); ``T = sqrt(S:S / 2)`` is the intensity of shear stresses and the
yield condition ``T <= tau_s``, i.e. ``sqrt(3) T <= sigma_y`` (von Mises). With hardening the
yield stress grows with the equivalent plastic strain ``peps = int sqrt(2/3 d eps_p : d eps_p)``:
``sigma_y = sigma_y0 + H peps``. The correction scales the trial deviator back to the yield
surface (radial return), which for ideal plasticity is exactly Wilkins' formula
``sigma = sigma_0 I + S tau_s / T``.
"""

from __future__ import annotations

import math

import numpy as np

SQRT3 = math.sqrt(3.0)


def shear_intensity(sigma: np.ndarray) -> np.ndarray:
    """``T = sqrt(S:S / 2)`` of Voigt stresses (..., 6)."""
    s = sigma[..., :3] - sigma[..., :3].mean(axis=-1, keepdims=True)
    return np.sqrt(0.5 * (s * s).sum(-1) + (sigma[..., 3:] ** 2).sum(-1))


def wilkins(trial: np.ndarray, peps: np.ndarray, mu: np.ndarray, sigma_y0: float, H: float):
    """Return-map trial stresses onto the yield surface.

    Parameters
    ----------
    trial : (..., 6) trial stresses ``sigma_n + D d_eps``
    peps : (...) equivalent plastic strain at the start of the step
    mu : (...) shear modulus at each point (the contrast material's is scaled)
    sigma_y0, H : initial yield stress in tension and the plastic modulus

    Returns
    -------
    sigma : (..., 6), peps : (...), yielding : (...) bool
    """
    T = shear_intensity(trial)
    sigma_y = sigma_y0 + H * peps
    yielding = SQRT3 * T > sigma_y
    if not yielding.any():
        return trial, peps, yielding
    eq = SQRT3 * T
    dpeps = np.where(yielding, (eq - sigma_y) / (3 * mu + H), 0.0)
    scale = np.where(yielding, 1.0 - 3 * mu * dpeps / np.where(yielding, eq, 1.0), 1.0)
    mean = trial[..., :3].mean(axis=-1, keepdims=True)
    sigma = trial * scale[..., None]
    sigma[..., :3] += mean * (1.0 - scale[..., None])  # the mean stress is left alone
    return sigma, peps + dpeps, yielding
