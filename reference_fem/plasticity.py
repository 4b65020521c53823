"""von Mises plasticity with linear isotropic hardening: radial return at quadrature points.

Pure, vectorised functions over all quadrature points; strains and stresses are Mandel vectors
(see :mod:`reference_fem.forms`), the first three components the normal ones. The state is
the plastic strain ``eps_p`` (Mandel, same shape as the strain) and the accumulated equivalent
plastic strain ``alpha``; the caller commits the returned state only after an equilibrium
iteration has converged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: trial yield function values below this fraction of the yield stress count as elastic, so
#: that round-off on a converged yield surface never triggers a return
YIELD_TOL = 1e-10


@dataclass(frozen=True)
class Return:
    """Result of :func:`radial_return` at ``n_qp`` points with ``nc`` Mandel components.

    Attributes
    ----------
    sigma : (n_qp, nc) stress
    tangent : (n_qp, nc, nc) consistent (algorithmic) tangent d sigma / d eps (None when not
        asked for)
    eps_p : (n_qp, nc) plastic strain
    alpha : (n_qp,) accumulated equivalent plastic strain (drives hardening)
    yielding : (n_qp,) bool, points returned to the yield surface
    strain : (n_qp, nc) the total strain it is the state of
    """

    sigma: np.ndarray
    tangent: np.ndarray
    eps_p: np.ndarray
    alpha: np.ndarray
    yielding: np.ndarray
    strain: np.ndarray


def deviator(x: np.ndarray) -> np.ndarray:
    """Deviatoric part of Mandel vectors ``x``, shape ``(n, nc)``."""
    out = x.copy()
    out[:, :3] -= x[:, :3].mean(axis=1, keepdims=True)
    return out


def equivalent_plastic_strain(eps_p: np.ndarray) -> np.ndarray:
    """``sqrt(2/3 eps_p : eps_p)``, shape ``(n,)`` (the probes' ``peps``)."""
    return np.sqrt(2.0 / 3.0 * np.einsum("qc,qc->q", eps_p, eps_p))


def radial_return(eps, eps_p, alpha, lam: float, mu: float, sigma_y: float, H: float,
                  tangent: bool = True) -> Return:
    """Stress, tangent and trial state for the total strain ``eps`` from the committed state.

    Parameters
    ----------
    eps : (n_qp, nc) total strain
    eps_p, alpha : committed plastic strain (n_qp, nc) and equivalent plastic strain (n_qp,)
    lam, mu : Lame constants (Pa)
    sigma_y : initial uniaxial yield stress (Pa), ``sqrt(3) tau_s``
    H : plastic hardening modulus (Pa), ``sigma_y(alpha) = sigma_y + H alpha`` (0 = ideal)
    tangent : also the consistent tangent (an explicit step needs the stress only)

    Notes
    -----
    Trial stress ``C (eps - eps_p)``; if ``q_tr = sqrt(3/2) |s_tr|`` exceeds the current yield
    stress, ``dgamma = (q_tr - sigma_y(alpha)) / (3 mu + H)`` and the deviator is scaled back
    onto the surface (Wilkins' correction, the paper's (16)). Tangent (de Souza Neto et al.,
    *Computational Methods for Plasticity*, 2008, box 7.4):
    ``kappa m m^T + 2 mu (1 - 3 mu dgamma / q_tr) P_dev + 6 mu^2 (dgamma / q_tr - 1 / (3 mu + H)) n n^T``.
    """
    nq, nc = eps.shape
    m = np.zeros(nc)
    m[:3] = 1.0
    eye = np.eye(nc)
    elastic = lam * np.outer(m, m) + 2.0 * mu * eye

    # the trial state at every point, column by column (reductions over the few components
    # cost more than the arithmetic); the return only where points yield (few, usually)
    eps_e = eps - eps_p
    trace = eps_e[:, 0] + eps_e[:, 1] + eps_e[:, 2]
    s_tr = 2.0 * mu * eps_e
    for c in range(3):
        s_tr[:, c] -= 2.0 * mu / 3.0 * trace
    sigma = s_tr.copy()
    for c in range(3):
        sigma[:, c] += (lam + 2.0 * mu / 3.0) * trace
    norm = np.sqrt(np.einsum("qc,qc->q", s_tr, s_tr))
    q_tr = np.sqrt(1.5) * norm
    f = q_tr - (sigma_y + H * alpha)
    yielding = f > YIELD_TOL * sigma_y
    y = np.flatnonzero(yielding)
    if y.size:
        dgamma = f[y] / (3.0 * mu + H)
        n = s_tr[y] / norm[y, None]
        flow = np.sqrt(1.5) * dgamma[:, None] * n  # plastic strain increment
        sigma[y] -= 2.0 * mu * flow
        eps_p, alpha = eps_p.copy(), alpha.copy()
        eps_p[y] += flow
        alpha[y] += dgamma
    if not tangent:
        return Return(sigma, None, eps_p, alpha, yielding, eps)
    tangent = np.broadcast_to(elastic, (nq, nc, nc)).copy()
    if y.size:
        ratio = dgamma / q_tr[y]
        kappa = lam + 2.0 * mu / 3.0
        p_dev = eye - np.outer(m, m) / 3.0
        tangent[y] = (
            kappa * np.outer(m, m)
            + 2.0 * mu * (1.0 - 3.0 * mu * ratio)[:, None, None] * p_dev
            + 6.0 * mu**2 * (ratio - 1.0 / (3.0 * mu + H))[:, None, None] * np.einsum("qa,qb->qab", n, n)
        )
    return Return(sigma, tangent, eps_p, alpha, yielding, eps)
