"""The elastic stiffness and mass of all modes stacked, applied without the coupled matrix.

``K x = K_h x + C_K x`` and ``M x = M_h x + C_M x``: ``K_h``, ``M_h`` are the block-diagonal
operators of the body without cut-outs (f = 1: different harmonics are orthogonal along x3),
and the corrections ``C`` carry ``f - 1``, which is nonzero only in the cut-out elements over
the cut-outs' x3 intervals. There the corrections are integrated at the Gauss-Legendre points
of those intervals (exact for the products of the kept modes, :mod:`smfem.inhomogeneity`):
the amplitudes are synthesized at the points, weighted by ``f - 1`` and projected back. The
cost grows with the cut-out's points times the modes, not with the square of the modes as
the coupled matrix does: at 400 harmonics on the notched strip it is a few per cent of one
solve with that matrix. Exact, so equal to the assembled coupled matrices to round-off.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from . import fourier
from .assembly import node_dofs
from .elements import DOFS_PER_NODE
from .sampling import ROWS, element_scatter, sample_operators


def cutout_points(model) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The Gauss-Legendre points of the cut-outs' x3 intervals: ``x3``, weights and ``f - 1``
    per cut-out element (ne, nq)."""
    live = model.cutout_elements
    inside = (model.factor[live] != 1.0).any(axis=0)
    return model.x3[inside], model.x3_weights[inside], model.factor[np.ix_(live, inside)] - 1.0


class StackedOperator:
    """``K x`` and ``M x`` of a model's modes stacked (``model.offsets``)."""

    def __init__(self, model):
        self.model = model
        S = model.systems
        if not model.coupling:
            self.K_h, self.M_h, self.cut = sp.block_diag([s.K for s in S], format="csr"), np.concatenate([s.M for s in S]), None
            return
        self.K_h = sp.block_diag([k for k, _ in model.homogeneous_blocks], format="csr")
        self.M_h = np.concatenate([m for _, m in model.homogeneous_blocks])
        live = model.cutout_elements
        x3, w, excess = cutout_points(model)
        psi = np.array([fourier.psi(s.mode, x3, model.body, model.length) for s in S])  # (n_modes, 2, nq)
        self.psi, self.psi_t = psi.transpose(1, 0, 2).copy(), psi.transpose(1, 2, 0).copy()  # per row type
        # stiffness: D B and B' at the section sample points of the cut-out elements, weights per point
        B = sample_operators(model, live)  # (n_modes, ne, ng, 6, d)
        ng, d = B.shape[2], B.shape[4]
        self.DB = (model.element_D(live, 1) @ B).reshape(-1, ng * 6, d)
        self.Bt = B.reshape(-1, ng * 6, d).transpose(0, 2, 1).copy()
        self.G = element_scatter(model, live)
        self.Gt = self.G.T.tocsr()
        self.k_weight = (model.ops.sample_weights[live][:, :, None] * excess[:, None, :] * w).reshape(-1, len(x3))  # (ne * ng, nq)
        # mass: each cut-out element's (f - 1) rho to its nodes, by their shares
        nodes, where = np.unique(model.mesh.elements[live], return_inverse=True)
        share = model.element_rho(live, 2) * model.ops.node_volume[live][:, :, None] * excess[:, None, :] * w  # (ne, nodes, nq)
        m_weight = np.zeros((len(nodes), len(x3)))
        np.add.at(m_weight, where.reshape(len(live), -1), share)
        self.m_weight = np.repeat(m_weight, DOFS_PER_NODE, axis=0)  # per node dof
        component = np.tile(np.arange(DOFS_PER_NODE), len(nodes))
        self.dofs_of_type = (np.flatnonzero(component < 2), np.flatnonzero(component == 2))
        dofs = node_dofs(nodes).ravel()
        self.H = sp.block_diag([s.T.T[:, dofs] for s in S], format="csr")  # node dofs -> stacked
        self.Ht = self.H.T.tocsr()
        self.cut = (len(S), len(live) * ng, len(nodes))

    def K(self, x: np.ndarray) -> np.ndarray:
        if self.cut is None:
            return self.K_h @ x
        n_modes, n_points, _ = self.cut
        a = (self.DB @ (self.Gt @ x).reshape(len(self.DB), -1, 1)).reshape(n_modes, n_points, 6).transpose(2, 1, 0)  # D B x, rows first
        back = np.empty_like(a)
        for t, rows in enumerate(ROWS):
            back[rows] = ((a[rows] @ self.psi[t]) * self.k_weight) @ self.psi_t[t]
        per_point = back.transpose(2, 1, 0).reshape(len(self.Bt), -1, 1)
        return self.K_h @ x + self.G @ (self.Bt @ per_point).ravel()

    def M(self, x: np.ndarray) -> np.ndarray:
        if self.cut is None:
            return self.M_h * x
        n_modes, _, n_nodes = self.cut
        u = (self.Ht @ x).reshape(n_modes, n_nodes * DOFS_PER_NODE).T  # (node dofs, modes)
        back = np.empty_like(u)
        for t, dofs in enumerate(self.dofs_of_type):  # in-plane components go as psi1, the x3 one as psi3
            back[dofs] = ((u[dofs] @ self.psi[t]) * self.m_weight[dofs]) @ self.psi_t[t]
        return self.M_h * x + self.H @ back.T.ravel()
