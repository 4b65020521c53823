"""Stress sample points of the nonlinear solver: strain synthesis and internal forces.

Stresses live at the 2 x 2 Gauss points ``(+-a, +-a)``, ``a = 1 / (2 sqrt 3)``, of each
element's moment-scheme strain field ``B0 + xi B1 + eta B2`` (only the retained linear terms),
times the quadrature points along x3. Because ``a^2 = 1/12``, the average over the four points
of ``B_g' D B_g`` is exactly the moment-scheme stiffness, so the internal forces (14) of an
elastic state equal ``K u``. Arrays of point data are shaped ``(n_elements, 4, n_x3, ...)``.
"""

from __future__ import annotations

import numpy as np

from . import fourier
from .assembly import element_dofs

GAUSS_A = 0.5 / np.sqrt(3.0)
GAUSS_XI = GAUSS_A * np.array([-1.0, 1.0, 1.0, -1.0])
GAUSS_ETA = GAUSS_A * np.array([-1.0, -1.0, 1.0, 1.0])


class SamplePoints:
    """Linear maps between mode amplitudes and the stresses and forces at the sample points.

    An isotropic D couples only strain rows with the same basis function along x3, so the
    elastic stress of a mode is ``psi(x3) * (D amplitude)``: D acts on the small per-element
    amplitudes, never on the large point arrays.
    """

    def __init__(self, model):
        self.model = model
        self.x3, self.w = model.x3, model.x3_weights
        self.factor = model.factor  # (n_elements, n_x3)
        self.dofs = element_dofs(model.mesh.elements)
        self.n_full = 3 * model.mesh.n_nodes
        self.B, self.psi = [], []
        for s in model.systems:
            p = fourier.wavenumber(s.mode, model.body, model.length)
            B0, B1, B2 = model.ops.at(p)
            self.B.append(B0[:, None] + GAUSS_XI[None, :, None, None] * B1[:, None] + GAUSS_ETA[None, :, None, None] * B2[:, None])
            psi1, psi3 = fourier.psi(s.mode, self.x3, model.body, model.length)
            self.psi.append(np.where(fourier.ROW_TYPE[None, :] == 0, psi1[:, None], psi3[:, None]))  # (n_x3, 6)
        self.psi_all = np.stack(self.psi)  # (n_modes, n_x3, 6)
        self.weight = 0.25 * model.ops.sqrt_g  # per element and Gauss point
        self.scale = self.factor[:, None, :, None]  # the contrast material's D is scaled

    def stress_amplitude(self, i: int, u: np.ndarray) -> np.ndarray:
        """``D B u`` (n_elements, 4, 6) of reduced amplitudes ``u`` of mode ``i``."""
        full = self.model.systems[i].T @ u
        return np.einsum("rs,egsk,ek->egr", self.model.D, self.B[i], full[self.dofs])

    def stress_of_mode(self, i: int, u: np.ndarray) -> np.ndarray:
        """Elastic stresses (n_elements, 4, n_x3, 6) of amplitudes ``u`` of mode ``i``."""
        return self.stress_amplitude(i, u)[:, :, None, :] * self.psi[i][None, None] * self.scale

    def stress(self, u_modes) -> np.ndarray:
        """Elastic stresses of all modes' amplitudes (a list of reduced vectors)."""
        amps = np.stack([self.stress_amplitude(i, u) for i, u in enumerate(u_modes)])
        return np.einsum("iqr,iegr->egqr", self.psi_all, amps, optimize=True) * self.scale

    def force_of_mode(self, i: int, sigma: np.ndarray) -> np.ndarray:
        """Internal force amplitudes (reduced) of mode ``i`` from stresses at the points (14)."""
        projected = np.einsum("q,qr,egqr->egr", self.w, self.psi[i], sigma)
        per_element = np.einsum("egrk,egr,e->ek", self.B[i], projected, self.weight)
        full = np.bincount(self.dofs.ravel(), per_element.ravel(), minlength=self.n_full)
        return self.model.systems[i].T.T @ full
