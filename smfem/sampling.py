"""Stress sample points of the nonlinear solver: strain synthesis and internal forces.

Stresses live at the 2 x 2 Gauss points ``(+-a, +-a)``, ``a = 1 / (2 sqrt 3)``, of each
element's moment-scheme strain field ``B0 + xi B1 + eta B2`` (only the retained linear terms),
times the quadrature points along x3. Because ``a^2 = 1/12``, the average over the four points
of ``B_g' D B_g`` is exactly the moment-scheme stiffness, so the internal forces (14) of an
elastic state equal ``K u``. Arrays of point data are shaped ``(n_elements, 4, n_x3, ...)``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

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
        # all modes at once: B of every mode, one sparse map from element dofs of every mode to
        # the stacked reduced amplitudes, and the x3 projection weights per stress row
        self.B_all = np.stack(self.B)  # (n_modes, n_elements, 4, 6, 12)
        ne = len(self.dofs)
        scatter = sp.csr_matrix((np.ones(self.dofs.size), (self.dofs.ravel(), np.arange(self.dofs.size))),
                                shape=(self.n_full, self.dofs.size))
        self.G = sp.block_diag([s.T.T @ scatter for s in model.systems], format="csr")
        self.Gt = self.G.T.tocsr()
        self.offsets = np.cumsum([0] + [s.T.shape[1] for s in model.systems])
        self.shape = (len(self.B), ne)
        self.W = (self.w[None, :, None] * self.psi_all).transpose(2, 1, 0)  # (6, n_x3, n_modes)
        self.psi_rows = np.ascontiguousarray(self.psi_all.transpose(2, 0, 1))  # (6, n_modes, n_x3)

    def stress_amplitude(self, i: int, u: np.ndarray) -> np.ndarray:
        """``D B u`` (n_elements, 4, 6) of reduced amplitudes ``u`` of mode ``i``."""
        full = self.model.systems[i].T @ u
        return np.einsum("rs,egsk,ek->egr", self.model.D, self.B[i], full[self.dofs])

    def stress_of_mode(self, i: int, u: np.ndarray) -> np.ndarray:
        """Elastic stresses (n_elements, 4, n_x3, 6) of amplitudes ``u`` of mode ``i``."""
        return self.stress_amplitude(i, u)[:, :, None, :] * self.psi[i][None, None] * self.scale

    def stress(self, u_modes) -> np.ndarray:
        """Elastic stresses of all modes' amplitudes (a list of reduced vectors, or stacked)."""
        u = np.concatenate(u_modes) if isinstance(u_modes, (list, tuple)) else u_modes
        n_modes, ne = self.shape
        per_element = (self.Gt @ u).reshape(n_modes, ne, 1, 12, 1)
        amps = (self.model.D @ (self.B_all @ per_element))[..., 0]  # D B u: (n_modes, ne, 4, 6)
        amps = amps.reshape(n_modes, ne * 4, 6).transpose(2, 1, 0)  # (6, ne*4, n_modes)
        out = amps @ self.psi_rows  # (6, ne*4, n_x3): one matrix product per stress row
        return out.reshape(6, ne, 4, -1).transpose(1, 2, 3, 0) * self.scale

    def forces(self, sigma: np.ndarray) -> np.ndarray:
        """Internal force amplitudes (14) of all modes, stacked, from stresses at the points."""
        n_modes, ne = self.shape
        rows = sigma.transpose(3, 0, 1, 2).reshape(6, ne * 4, -1)
        projected = (rows @ self.W).reshape(6, ne, 4, n_modes).transpose(3, 1, 2, 0)  # (modes, ne, 4, 6)
        per_element = (projected[..., None, :] @ self.B_all)[..., 0, :]  # (modes, ne, 4, 12)
        per_element = per_element.sum(axis=2) * self.weight[None, :, None]
        return self.G @ per_element.ravel()

    def force_of_mode(self, i: int, sigma: np.ndarray) -> np.ndarray:
        """Internal force amplitudes (reduced) of mode ``i`` from stresses at the points (14)."""
        projected = np.einsum("q,qr,egqr->egr", self.w, self.psi[i], sigma)
        per_element = np.einsum("egrk,egr,e->ek", self.B[i], projected, self.weight)
        full = np.bincount(self.dofs.ravel(), per_element.ravel(), minlength=self.n_full)
        return self.model.systems[i].T.T @ full
