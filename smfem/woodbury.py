"""The coupled ``K + a0 M`` of a body with short cut-outs: block-diagonal plus low rank (Woodbury).

``A = A_h + dA``: ``A_h`` is the body without cut-outs (f = 1), block-diagonal over the modes;
``dA`` carries ``f - 1``, nonzero only in the cut-out elements over the cut-outs' x3 intervals.
At an x3 point ``q`` of those intervals (:func:`smfem.inhomogeneity.x3_rule`) the strains of
every mode together are ``Ba U(q) + Bb W(q)``, with ``U, W`` the two series along x3 of each cut-out dof
(:class:`smfem.sampling.DofSeries`: its displacement, and the wavenumber-weighted series in
the other basis type), so ``dA = sum_q w_q Z_q' H_q Z_q`` with ``Z_q x = (U(q), W(q))`` and
``H_q`` the ``(f - 1)``-weighted energy of the cut-out elements in those values (moment-scheme
stiffness and lumped mass on ``U``). Its rank is at most the points times twice the cut-out dofs,
however many harmonics there are: the notched strip at 400 harmonics couples 4800
amplitudes through the notch, of rank 1968. With ``H_q = -F_q F_q'`` (``f < 1``) and
``V = F' Z``: ``A = A_h - V'V`` and ``A^-1 = A_h^-1 + A_h^-1 V' S^-1 V A_h^-1``,
``S = I - V A_h^-1 V'``, symmetric positive definite, inverted once (through its Cholesky
factor). A solve is two block-diagonal solves, the synthesis at the cut-out points (fewer
combinations of them, :func:`point_combinations`) and one dense product of the rank's
size, against a sparse factorization whose fill grows with the square of the modes.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from . import fourier
from .coupling import cutout_points
from .elements import DOFS_PER_NODE
from .linalg import factorize_spd, stacked_step
from .sampling import DofSeries, carried_dofs, linear_parts, rows_of, series_index


def cutout_dofs(model) -> np.ndarray:
    """Full dofs of the cut-out elements' nodes that some mode carries."""
    return carried_dofs(model, np.unique(model.mesh.elements[model.cutout_elements]))


#: singular values of the modes at a group's points below this share of the largest are
#: dropped (:func:`point_combinations`)
COMBINE_TOL = 1e-13


def point_combinations(model) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cut-out points as fewer combinations with the same energies: ``(x3, combine,
    excess)``, ``combine`` (nq, r) and ``excess`` (cut-out elements, r) the cut-out factors
    each combination's points share.

    Points whose cut-out elements have the same factors (``excess``) share ``H_q`` up to their
    weight, so there ``dA = sum_q w_q Z_q' H Z_q`` needs only the span of the modes' values
    ``sqrt(w_q) psi(q)``: with the columns of ``P`` an orthonormal basis of it (an SVD, to
    :data:`COMBINE_TOL`), the combinations ``sqrt(w_q) P[q, i]`` give the same sum. The
    modes have fewer independent values there than the points that integrate their products
    where the modes share a symmetry (notched_cylinder refine 8 at 160 harmonics: 107 of 248);
    on a short interval the transplanted rule's points already are about as many as those
    (moving_load_notched quad9 at 480 harmonics: 37 of 37)."""
    x3, w, excess = cutout_points(model)
    psi = np.array([fourier.psi(s.mode, x3, model.body, model.length) for s in model.systems])  # (modes, 2, nq)
    values = np.sqrt(w)[:, None] * psi.transpose(2, 1, 0).reshape(len(x3), -1)  # (nq, 2 modes)
    _, group = np.unique(excess.T, axis=0, return_inverse=True)
    columns, representative = [], []  # a point of each combination
    for g in range(group.max() + 1):
        at = np.flatnonzero(group.ravel() == g)
        P, sv, _ = np.linalg.svd(values[at], full_matrices=False)
        P = P[:, sv > COMBINE_TOL * sv[0]]
        block = np.zeros((len(x3), P.shape[1]))
        block[at] = np.sqrt(w[at])[:, None] * P
        columns.append(block)
        representative += [at[0]] * P.shape[1]
    return x3, np.concatenate(columns, axis=1), excess[:, representative]


def rank_bound(model) -> int:
    """The most the correction's rank can be: point combinations times the two series per dof."""
    return point_combinations(model)[1].shape[1] * 2 * len(cutout_dofs(model))


class CutoutWoodbury:
    """``solve(b)`` with the coupled elastic ``K + a0 M`` of ``model``, as described above."""

    def __init__(self, model, a0: float):
        x3, combine, excess = point_combinations(model)
        dofs = cutout_dofs(model)
        self.series = DofSeries(model, dofs, x3, np.ones(combine.shape[1]), combine)  # at the combinations
        E = rows_of(model, dofs)  # reduced -> cut-out dofs, per mode
        H = self._energies(model, a0, dofs, excess)  # (combinations, 2 dofs, 2 dofs), f - 1 < 0
        # -H_q = F_q F_q' (the weights are in the combinations): the correction's factors, each
        # combination's padded to a common rank
        lam, Y = np.linalg.eigh(-H)
        keep = lam > 1e-12 * lam.max()
        rank = int(keep.sum(axis=1).max())
        order = np.argsort(-lam, axis=1)[:, :rank]
        lam, Y = np.take_along_axis(lam, order, 1), np.take_along_axis(Y, order[:, None, :], 2)
        F = Y * np.sqrt(np.where(np.take_along_axis(keep, order, 1), lam, 0.0))[:, None, :]  # (nq, 2 dofs, rank)
        self.F = F[:, self.series.source]  # on the series' sorted rows
        # A_h: the body without cut-outs, block-diagonal
        blocks = model.homogeneous_blocks
        self.base = factorize_spd(stacked_step(blocks, a0))
        # S = I - V A_h^-1 V' = I - sum_l W_l G_l W_l', G_l the cut-out dofs' block of A_l^-1
        # one solve with the block-diagonal factors and a column per cut-out dof, unit in every
        # mode's block at once (the blocks do not mix), gives every mode's block of A^-1 there
        columns, o = self.base.solve(sp.vstack([Ei.T for Ei in E]).toarray()), model.offsets
        G = np.stack([Ei @ columns[o[i]:o[i + 1]] for i, Ei in enumerate(E)])  # (modes, dofs, dofs)
        capacitance = self._capacitance(F, G, dofs)
        # S^-1 itself (its lower triangle), applied by one symmetric product a solve: it reads the
        # triangle once where the Cholesky factor's two triangular solves read it twice. The
        # inverse costs twice the factor's flops, and pays from a few hundred solves on
        # (benchmarks/README.md, coupled_profile.py); equal to 1.5e-13
        factor, _ = la.cho_factor(capacitance, lower=True, check_finite=False, overwrite_a=True)
        self.inverse, info = la.lapack.dpotri(factor, lower=1, overwrite_c=1)
        if info:
            raise la.LinAlgError(f"dpotri: the capacitance is singular ({info})")
        self.rank = len(capacitance)

    def _capacitance(self, F: np.ndarray, G: np.ndarray, dofs: np.ndarray) -> np.ndarray:
        """The lower triangle of ``S = I - V A_h^-1 V'``, ``V A_h^-1 V' = sum_l W_l G_l W_l'``
        summed over the modes first. With ``Z_l`` the series (U and W) of unit amplitudes at the
        points, the kernel ``K[(q, a, d), (p, b, e)] = sum_l Z_l[q, a, d] G_l[d, e] Z_l[p, b, e]``,
        and ``Z_l`` depends on the dof ``d`` only through its basis type: per pair of types, one
        matrix product over the modes gives every pair of points and dofs, and ``F_q' K F_p``
        one product per pair of points. Only the pairs ``p <= q`` are formed (``S`` is
        symmetric, the Cholesky factor reads the lower triangle): ``(q (q + 1) / 2) (2 n)^2``
        modes flops and ``q (q + 1) (2 n)^2 rank``, against ``rank^2`` times the coupled
        amplitudes of forming each mode's ``W_l G_l W_l'``."""
        nq, two_n, rank = F.shape
        n, modes = two_n // 2, len(G)
        comp_type = (dofs % DOFS_PER_NODE == 2).astype(int)  # in-plane components go as psi1, the x3 one as psi3
        psi, k = self.series.psi, self.series.k  # (2, modes, nq), (modes,)
        Z = [np.stack([psi[t], k[:, None] * psi[1 - t]], axis=2) for t in (0, 1)]  # per type: (modes, nq, U/W)
        q, p = np.tril_indices(nq)  # the pairs of points of the lower triangle
        kernel = np.empty((len(q), 2, n, 2, n))  # K's blocks (q, p)
        for t in (0, 1):
            for u in (0, 1):
                d, e = np.flatnonzero(comp_type == t), np.flatnonzero(comp_type == u)
                products = (Z[t][:, q, :, None] * Z[u][:, p, None, :]).reshape(modes, -1)  # (modes, pairs 2 2)
                summed = products.T @ G[:, d[:, None], e[None, :]].reshape(modes, -1)  # (pairs 2 2, d e)
                kernel[:, :, d[:, None], :, e[None, :]] = (summed.reshape(len(q), 2, 2, len(d), len(e))
                                                           .transpose(3, 4, 0, 1, 2))
        kernel = kernel.reshape(len(q), two_n, two_n)
        capacitance = np.zeros((nq, rank, nq, rank))
        capacitance[q, :, p, :] = -np.matmul(np.matmul(F[q].transpose(0, 2, 1), kernel), F[p])
        capacitance = capacitance.reshape(nq * rank, nq * rank)
        capacitance[np.diag_indices_from(capacitance)] += 1.0
        return capacitance

    @staticmethod
    def _energies(model, a0, dofs, excess):
        """``H_q`` (nq, 2 n, 2 n) on ``(U, W)`` of the cut-out dofs: the (f - 1)-weighted
        element stiffness, ``Ba U + Bb W`` at the element's sample points, and lumped mass."""
        live = model.cutout_elements
        ops = model.ops.subset(live)
        Ba, Bb = linear_parts(ops)  # (ne, ng, 6, d)
        d = Ba.shape[-1]
        B = np.concatenate([Ba, Bb], axis=3)  # (ne, ng, 6, 2 d): on (U_e, W_e)
        D = model.element_D(live)
        k = np.einsum(f"eg,egri,{'e' * (D.ndim - 2)}rs,egsj->eij", ops.sample_weights, B, D, B, optimize=True)
        k[:, np.arange(d), np.arange(d)] += a0 * model.element_rho(live, 1) * np.repeat(ops.node_volume, DOFS_PER_NODE, axis=1)  # lumped mass on U
        # scatter each element's (U_e, W_e) into the cut-out dofs' (U, W), (f - 1)-weighted per
        # point: H_q = sum_e excess[e, q] k_e, one sparse product over all elements
        n = len(dofs)
        index = series_index(dofs, model.mesh.elements[live])  # (ne, 2 d)
        ok = (index[:, :, None] >= 0) & (index[:, None, :] >= 0)
        flat = (index[:, :, None] * (2 * n) + index[:, None, :])[ok]
        owner = np.broadcast_to(np.arange(len(live))[:, None, None], ok.shape)[ok]
        scatter = sp.csr_matrix((k[ok], (flat, owner)), shape=((2 * n) ** 2, len(live)))
        return (scatter @ excess).T.reshape(-1, 2 * n, 2 * n)

    def _V(self, x: np.ndarray) -> np.ndarray:
        """``V x`` (nq, rank) of stacked amplitudes: one product per point, batched (an
        ``einsum`` with ``optimize`` sought its path at every call: 0.1 of the notched strip's
        1.2 CPU s)."""
        return np.matmul(self.series.values(x).T[:, None, :], self.F)[:, 0, :]

    def _Vt(self, y: np.ndarray) -> np.ndarray:
        """``V' y`` of ``y`` (nq, rank), stacked amplitudes."""
        return self.series.project(np.matmul(self.F, y[:, :, None])[:, :, 0].T)

    def solve(self, b: np.ndarray) -> np.ndarray:
        y = self.base.solve(b)
        v = self._V(y)
        z = la.blas.dsymv(1.0, self.inverse, v.ravel(), lower=1).reshape(v.shape)
        return y + self.base.solve(self._Vt(z))

