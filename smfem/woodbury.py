"""The coupled ``K + a0 M`` of a body with short cut-outs: block-diagonal plus low rank (Woodbury).

``A = A_h + dA``: ``A_h`` is the body without cut-outs (f = 1), block-diagonal over the modes;
``dA`` carries ``f - 1``, nonzero only in the cut-out elements over the cut-outs' x3 intervals.
At a Gauss-Legendre point ``q`` of those intervals the strains of every mode together are
``Ba U(q) + Bb' U'(q)``, with ``U(q)`` the synthesized displacement of the cut-out nodes and
``U'`` its x3 derivative, so ``dA = sum_q w_q Z_q' H_q Z_q`` with ``Z_q x = (U(q), U'(q))`` and
``H_q`` the ``(f - 1)``-weighted energy of the cut-out elements in those nodal values (moment-
scheme stiffness and lumped mass). Its rank is at most the points times twice the cut-out
dofs, however many harmonics there are: the notched strip at 400 harmonics couples 4800
amplitudes through the notch, of rank 1968. With ``H_q = -F_q F_q'`` (``f < 1``) and
``V = F' Z``: ``A = A_h - V'V`` and ``A^-1 = A_h^-1 + A_h^-1 V' S^-1 V A_h^-1``,
``S = I - V A_h^-1 V'``, symmetric positive definite, Cholesky-factorized once. A solve is two
block-diagonal solves, the synthesis at the cut-out points and one dense solve of the rank's
size, against a sparse factorization whose fill grows with the square of the modes.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from . import fourier
from .assembly import element_dofs, node_dofs
from .coupling import cutout_points
from .elements import DOFS_PER_NODE
from .linalg import factorize_spd


def cutout_dofs(model) -> np.ndarray:
    """Full dofs of the cut-out elements' nodes that some mode carries."""
    nodes = np.unique(model.mesh.elements[model.cutout_elements])
    dofs = node_dofs(nodes).ravel()
    carried = np.zeros(len(dofs), bool)
    for s in model.systems:
        carried |= np.asarray(abs(s.T[dofs]).sum(axis=1)).ravel() > 0
    return dofs[carried]


def rank_bound(model) -> int:
    """The most the correction's rank can be: points times values and derivatives per dof."""
    return len(cutout_points(model)[0]) * 2 * len(cutout_dofs(model))


class CutoutWoodbury:
    """``solve(b)`` with the coupled elastic ``K + a0 M`` of ``model``, as described above."""

    def __init__(self, model, a0: float):
        S = model.systems
        x3, w, excess = cutout_points(model)
        dofs = cutout_dofs(model)
        n_dof = len(dofs)
        comp_type = (dofs % DOFS_PER_NODE == 2).astype(int)  # in-plane components go as psi1, the x3 one as psi3
        # basis values and x3 derivatives per mode, point and dof: d/dx psi(p x) = p psi(p x + pi / 2)
        p = np.array([fourier.wavenumber(s.mode, model.body, model.length) for s in S])
        value = np.array([fourier.psi(s.mode, x3, model.body, model.length) for s in S])  # (modes, 2, nq)
        slope = np.array([k * np.array(fourier.psi(s.mode, x3 + (math.pi / (2 * k) if k else 0.0), model.body, model.length))
                          for s, k in zip(S, p)])
        self.value, self.slope = value[:, comp_type].transpose(0, 2, 1), slope[:, comp_type].transpose(0, 2, 1)  # (modes, nq, dofs)
        E = [sp.csr_matrix(s.T[dofs]) for s in S]  # reduced -> cut-out dofs, per mode
        self.E = sp.block_diag(E, format="csr")  # stacked amplitudes -> (modes, dofs)
        self.Et = self.E.T.tocsr()
        H = self._energies(model, a0, dofs, comp_type, excess)  # (nq, 2 dofs, 2 dofs), f - 1 < 0
        # -w_q H_q = F_q F_q': the correction's factors, each point's padded to a common rank
        lam, Y = np.linalg.eigh(-w[:, None, None] * H)
        keep = lam > 1e-12 * lam.max()
        rank = int(keep.sum(axis=1).max())
        order = np.argsort(-lam, axis=1)[:, :rank]
        lam, Y = np.take_along_axis(lam, order, 1), np.take_along_axis(Y, order[:, None, :], 2)
        self.F = Y * np.sqrt(np.where(np.take_along_axis(keep, order, 1), lam, 0.0))[:, None, :]  # (nq, 2 dofs, rank)
        self.offsets, self.n_dof = model.offsets, n_dof
        # A_h: the body without cut-outs, block-diagonal
        blocks = model.homogeneous_blocks
        self.base = factorize_spd(sp.block_diag([k + sp.diags(a0 * m) for k, m in blocks], format="csr"))
        # S = I - V A_h^-1 V' = I - sum_l W_l G_l W_l', G_l the cut-out dofs' block of A_l^-1
        lus = [factorize_spd(k + sp.diags(a0 * m)) for k, m in blocks]
        Y = []
        for i, (lu, Ei) in enumerate(zip(lus, E)):
            lam, Q = np.linalg.eigh(Ei @ lu.solve(Ei.T.toarray()))  # G_l, semidefinite where a mode lacks a dof
            root = Q * np.sqrt(np.clip(lam, 0.0, None))  # G_l = root root'
            W = (np.einsum("qdr,qd->qrd", self.F[:, :n_dof], self.value[i], optimize=True)
                 + np.einsum("qdr,qd->qrd", self.F[:, n_dof:], self.slope[i], optimize=True)).reshape(-1, n_dof)
            Y.append(W @ root)
        Y = np.hstack(Y)
        # I - Y Y' in the lower triangle, one symmetric rank-k update
        capacitance = la.blas.dsyrk(-1.0, Y, beta=1.0, c=np.eye(len(Y)), lower=1)
        self.chol = la.cho_factor(capacitance, lower=True, check_finite=False, overwrite_a=True)
        self.rank, self.n_modes = len(Y), len(S)

    @staticmethod
    def _energies(model, a0, dofs, comp_type, excess):
        """``H_q`` (nq, 2 n, 2 n) on ``(U, U')`` of the cut-out dofs: the (f - 1)-weighted
        element stiffness, ``Ba U + Bb' U'`` at the element's sample points, and lumped mass."""
        live = model.cutout_elements
        ops = model.ops.subset(live)
        Ba, Bb = ops.sample_linear_parts()  # (ne, ng, 6, d)
        d = Ba.shape[-1]
        # Bb acts on the x3 derivative: a row varies as psi_row(p x), its derivative term as
        # p psi_comp(p x + pi / 2), which is +-psi_row: the sign per row and component type
        sign = _derivative_signs(model)
        comp_type = (np.arange(d) % DOFS_PER_NODE == 2).astype(int)  # element dof -> its component's type
        linked = fourier.ROW_TYPE[:, None] != comp_type[None, :]
        if np.any(Ba[..., linked]) or np.any(Bb[..., ~linked]):
            raise ValueError("a strain row mixes basis types: no nodal form along x3")
        Bb = Bb * sign[fourier.ROW_TYPE][:, comp_type]
        B = np.concatenate([Ba, Bb], axis=3)  # (ne, ng, 6, 2 d): on (U_e, U'_e)
        D = model.element_D(live)
        k = np.einsum(f"eg,egri,{'e' * (D.ndim - 2)}rs,egsj->eij", ops.sample_weights, B, D, B, optimize=True)
        k[:, np.arange(d), np.arange(d)] += a0 * model.element_rho(live, 1) * np.repeat(ops.node_volume, DOFS_PER_NODE, axis=1)  # lumped mass on U
        # scatter each element's (U_e, U'_e) into the cut-out dofs' (U, U'), (f - 1)-weighted per
        # point: H_q = sum_e excess[e, q] k_e, one sparse product over all elements
        n = len(dofs)
        local = element_dofs(model.mesh.elements[live])
        position = np.searchsorted(dofs, local)
        index = np.where(dofs[np.minimum(position, n - 1)] == local, position, -1)  # dofs no mode carries: -1
        index = np.concatenate([index, np.where(index >= 0, index + n, -1)], axis=1)  # (ne, 2 d)
        ok = (index[:, :, None] >= 0) & (index[:, None, :] >= 0)
        flat = (index[:, :, None] * (2 * n) + index[:, None, :])[ok]
        owner = np.broadcast_to(np.arange(len(live))[:, None, None], ok.shape)[ok]
        scatter = sp.csr_matrix((k[ok], (flat, owner)), shape=((2 * n) ** 2, len(live)))
        return (scatter @ excess).T.reshape(-1, 2 * n, 2 * n)

    def _V(self, x: np.ndarray) -> np.ndarray:
        """``V x`` (nq, rank) of stacked amplitudes."""
        N = (self.E @ x).reshape(self.n_modes, self.n_dof)
        U = np.einsum("lqd,ld->qd", self.value, N, optimize=True)
        dU = np.einsum("lqd,ld->qd", self.slope, N, optimize=True)
        n = self.n_dof
        return np.einsum("qdr,qd->qr", self.F[:, :n], U) + np.einsum("qdr,qd->qr", self.F[:, n:], dU)

    def _Vt(self, y: np.ndarray) -> np.ndarray:
        """``V' y`` of ``y`` (nq, rank), stacked amplitudes."""
        n = self.n_dof
        U, dU = np.einsum("qdr,qr->qd", self.F[:, :n], y), np.einsum("qdr,qr->qd", self.F[:, n:], y)
        N = np.einsum("lqd,qd->ld", self.value, U, optimize=True) + np.einsum("lqd,qd->ld", self.slope, dU, optimize=True)
        return self.Et @ N.ravel()

    def solve(self, b: np.ndarray) -> np.ndarray:
        y = self.base.solve(b)
        v = self._V(y)
        z = la.cho_solve(self.chol, v.ravel(), check_finite=False).reshape(v.shape)
        return y + self.base.solve(self._Vt(z))


def _derivative_signs(model) -> np.ndarray:
    """``s[row type, component type]`` with ``psi_row(p x) = s psi_comp(p x + pi / 2)`` for the
    types that a derivative along x3 links (the others are unused); the same for every mode,
    checked on each."""
    x = np.array([0.3, 1.1])
    s = np.zeros((2, 2))
    for m in (mode for mode in model.modes if mode.l > 0):
        k = fourier.wavenumber(m, model.body, model.length)
        at, shifted = fourier.psi(m, x / k, model.body, model.length), fourier.psi(m, x / k + math.pi / (2 * k), model.body, model.length)
        for r, c in ((0, 1), (1, 0)):
            ratio = at[r] / shifted[c]
            if not np.allclose(ratio, ratio[0]) or not np.isclose(abs(ratio[0]), 1.0) or s[r, c] == -np.sign(ratio[0]):
                raise ValueError(f"mode {m}: the x3 derivative does not map psi{c} onto psi{r} alike for every mode")
            s[r, c] = np.sign(ratio[0])
    return s
