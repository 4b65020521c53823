"""The elastic stiffness and mass of all modes stacked, applied without the coupled matrix.

``K x = K_h x + C_K x`` and ``M x = M_h x + C_M x``: ``K_h``, ``M_h`` are the block-diagonal
operators of the body without cut-outs (f = 1: different harmonics are orthogonal along x3),
and the corrections ``C`` carry ``f - 1``, which is nonzero only in the cut-out elements over
the cut-outs' x3 intervals. There the corrections are integrated at the x3 points of those
intervals (exact for the products of the kept modes, :func:`smfem.inhomogeneity.x3_rule`):
the amplitudes are synthesized at the points, weighted by ``f - 1`` and projected back. The
cost grows with the cut-out's points times the modes, not with the square of the modes as
the coupled matrix does: at 400 harmonics on the notched strip it is a few per cent of one
solve with that matrix. Exact, so equal to the assembled coupled matrices to round-off.
"""

from __future__ import annotations

import numpy as np

from .elements import DOFS_PER_NODE
from .linalg import block_diagonal
from .sampling import DofSeries, carried_dofs, section_maps


def cutout_points(model) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The x3 points of the cut-outs' intervals: ``x3``, weights and ``f - 1`` per cut-out
    element (ne, nq)."""
    live = model.cutout_elements
    inside = (model.factor[live] != 1.0).any(axis=0)
    return model.x3[inside], model.x3_weights[inside], model.factor[np.ix_(live, inside)] - 1.0


class StackedOperator:
    """``K x`` and ``M x`` of a model's modes stacked (``model.offsets``)."""

    def __init__(self, model):
        self.model = model
        S = model.systems
        if not model.coupling:
            self.K_h, self.M_h, self.series = block_diagonal([s.K for s in S]), np.concatenate([s.M for s in S]), None
            return
        self.K_h = block_diagonal([k for k, _ in model.homogeneous_blocks])
        self.M_h = np.concatenate([m for _, m in model.homogeneous_blocks])
        live = model.cutout_elements
        x3, w, excess = cutout_points(model)
        nodes = np.unique(model.mesh.elements[live])
        dofs = carried_dofs(model, nodes)
        self.series = DofSeries(model, dofs, x3, w)
        # stiffness: the stresses at the cut-out elements' sample points, weighted by f - 1
        self.to_stress, self.from_stress = section_maps(model, self.series, dofs, live)
        self.excess = excess[None, :, None, :]  # against the stresses (6, ne, ng, nq)
        self.point_shape = (6, len(live), model.ops.sample_weights.shape[1], len(x3))
        # mass: each cut-out element's (f - 1) rho to its nodes, by their shares
        where = np.searchsorted(nodes, model.mesh.elements[live])
        share = model.element_rho(live, 2) * model.ops.node_volume[live][:, :, None] * excess[:, None, :]  # (ne, nodes, nq)
        m_weight = np.zeros((len(nodes), len(x3)))
        np.add.at(m_weight, where, share)
        self.m_weight = m_weight[np.searchsorted(nodes, dofs // DOFS_PER_NODE)]  # per carried dof
        self.values_rows = self.series.row[:len(dofs)]  # the sorted rows of the displacements U (not of W)

    def K(self, x: np.ndarray) -> np.ndarray:
        if self.series is None:
            return self.K_h @ x
        stress = (self.to_stress @ self.series.values(x)).reshape(self.point_shape) * self.excess
        return self.K_h @ x + self.series.project(self.from_stress @ stress.reshape(-1, self.point_shape[3]))

    def M(self, x: np.ndarray) -> np.ndarray:
        if self.series is None:
            return self.M_h * x
        values = self.series.values(x)
        duals = np.zeros_like(values)
        duals[self.values_rows] = values[self.values_rows] * self.m_weight
        return self.M_h * x + self.series.project(duals)
