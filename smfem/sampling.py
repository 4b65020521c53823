"""Stress sample points of the nonlinear solver: strain synthesis and internal forces.

Stresses live at the element's sample points in the section (the moment scheme: its 2 x 2
Gauss points, :mod:`smfem.element`) times Gauss-Legendre points along x3 on the pieces between
cut-out edges. The section points integrate the element's stiffness exactly
(:mod:`smfem.elements`) and the x3 rule the products of the kept modes, so the internal
forces of an elastic state are ``K u`` with the exact coupling: the plastic strains then can
only soften what ``K`` holds, and the iterations converge.

The points cover only the fundamental domain of the modes' symmetry along x3 (prism, odd
harmonics only: half the span; ring, harmonics that are multiples of n, cosine family only:
0 ... pi / n), each weighted for all its images: the plastic state repeats there. Point arrays
are shaped ``(6, n_elements, n_section_points, n_x3)``: stress rows first, x3 last.
"""

from __future__ import annotations

import math
from functools import reduce

import numpy as np
import scipy.sparse as sp

from . import fourier, inhomogeneity
from .assembly import element_dofs
from .elements import DOFS_PER_NODE


def _rows_of_type(t: int) -> slice:
    """The stress rows of basis type ``t``, a slice (a view, not a copy, per synthesis)."""
    rows = np.flatnonzero(fourier.ROW_TYPE == t)
    assert np.array_equal(rows, np.arange(rows[0], rows[-1] + 1)), "rows of one type must be contiguous"
    return slice(int(rows[0]), int(rows[-1]) + 1)


#: stress rows by basis type along x3 (0: psi1, 1: psi3)
ROWS = (_rows_of_type(0), _rows_of_type(1))


def sample_operators(model, elements: np.ndarray | slice = slice(None)) -> np.ndarray:
    """``B`` of every mode at the sample points of ``elements``: (n_modes, ne, ng, 6, d)."""
    ops = model.ops.subset(np.arange(model.mesh.n_elements)[elements])
    return np.stack([ops.at_samples(fourier.wavenumber(s.mode, model.body, model.length)) for s in model.systems])


def element_scatter(model, elements: np.ndarray | slice = slice(None)) -> sp.csr_matrix:
    """The sparse map from per-mode element-dof values (n_modes, ne, d), raveled, to the
    stacked reduced amplitudes; its transpose gathers the element dofs of every mode."""
    dofs = element_dofs(model.mesh.elements[elements])
    n_full = DOFS_PER_NODE * model.mesh.n_nodes
    scatter = sp.csr_matrix((np.ones(dofs.size), (dofs.ravel(), np.arange(dofs.size))), shape=(n_full, dofs.size))
    return sp.block_diag([s.T.T @ scatter for s in model.systems], format="csr")


class Symmetry:
    """The fundamental domain ``[0, width]`` of the modes along x3 and the images of its points.

    ``copies`` images of the domain tile the period, mirrored (reflection about both ends) or
    turned (rotation by ``width``); ``width = period`` with one copy where there is no symmetry,
    and ``width = 0`` for an axisymmetric ring (one point stands for the whole circle).
    """

    def __init__(self, model):
        case, modes = model.case, model.modes
        self.period = 2 * math.pi if model.body == "ring" else model.length
        self.width, self.copies, self.mirror = self.period, 1, False
        if model.body != "ring":
            if all(m.l % 2 == 1 for m in modes):
                self.width, self.copies, self.mirror = self.period / 2, 2, True
        else:
            n = reduce(math.gcd, (m.l for m in modes))
            mirror = {m.family for m in modes} == {"c"}
            if n == 0:
                self.width, self.copies, self.mirror = 0.0, 1, False
            elif n > 1 or mirror:
                self.width = self.period / n / (2 if mirror else 1)
                self.copies, self.mirror = n * (2 if mirror else 1), mirror
        if self.copies > 1 and (case.cutouts or case.variation) and not self._shared_by(case, model.mesh):
            self.width, self.copies, self.mirror = self.period, 1, False

    def images(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every image of the points ``x`` over the period, sorted, the point each is of, and
        whether it is a mirror image (where the psi3 stress rows change sign)."""
        if self.width == 0.0:
            return x, np.arange(len(x)), np.zeros(len(x), bool)
        k = np.arange(self.copies // (2 if self.mirror else 1))
        turned = [(x[None, :] + 2 * self.width * k[:, None]) if self.mirror else x[None, :] + self.width * k[:, None]]
        if self.mirror:
            turned.append(2 * self.width * (k[:, None] + 1) - x[None, :])
        full = np.concatenate([t.ravel() for t in turned]) % self.period
        index = np.tile(np.arange(len(x)), len(turned) * len(k))
        mirrored = np.repeat(np.arange(len(turned)) == 1, len(k) * len(x))
        order = np.argsort(full, kind="stable")
        return full[order], index[order], mirrored[order]

    def _shared_by(self, case, mesh) -> bool:
        """Whether the cut-outs repeat on every image of the domain (the modes' symmetry is the
        problem's, so they should)."""
        x = (np.arange(4096) + 0.5 * math.sqrt(2) - 0.5) * self.width / 4096
        full, index, _ = self.images(x)
        return np.array_equal(inhomogeneity.element_factor(case, mesh, full),
                              inhomogeneity.element_factor(case, mesh, x)[:, index])


def sample_points(model, oversampling: float, at_least: int = 0) -> tuple[np.ndarray, np.ndarray, Symmetry]:
    """Points and weights along x3 over the fundamental domain (each weighted for its images):
    ``oversampling`` times the Gauss-Legendre points that integrate the modes' products exactly,
    and more where that makes fewer than ``at_least`` (few harmonics still have plastic zones to
    resolve along x3)."""
    sym = Symmetry(model)
    if sym.width == 0.0:
        return np.zeros(1), np.full(1, sym.period), sym
    top_k = 2 * max(fourier.wavenumber(m, model.body, model.length) for m in model.modes)
    edges = inhomogeneity.cut_edges(model.case, 0.0, sym.width)
    x, w = inhomogeneity.gauss_pieces(edges, top_k, oversampling)
    if len(x) < at_least:
        x, w = inhomogeneity.gauss_pieces(edges, top_k, oversampling * at_least / len(x))
    return x, w * sym.copies, sym


class SamplePoints:
    """Linear maps between mode amplitudes and stresses and forces at the sample points.

    An isotropic D couples only strain rows with the same basis function along x3, so the
    elastic stress of a mode is ``psi(x3) * (D B u)``: D acts on the small per-element
    amplitudes; the sums over modes and points are one matrix product per row type.
    """

    def __init__(self, model, oversampling: float, at_least: int = 0):
        self.model = model
        self.x3, self.w, self.symmetry = sample_points(model, oversampling, at_least)
        self.images = self.symmetry.images(self.x3)  # fixed: fields, zones and probes map onto the points
        self.factor = inhomogeneity.element_factor(model.case, model.mesh, self.x3)  # (ne, n_x3)
        self.scale = self.factor[None, :, None, :]
        self.homogeneous = bool(np.all(self.factor == 1.0))  # no contrast material: no scaling
        psi = np.array([fourier.psi(s.mode, self.x3, model.body, model.length) for s in model.systems])
        self.psi = psi.transpose(1, 0, 2).copy()  # (2, n_modes, n_x3): synthesis per row type
        self.psi_w = (psi * self.w).transpose(1, 2, 0).copy()  # (2, n_x3, n_modes): weighted projection
        B = sample_operators(model)  # (n_modes, ne, ng, 6, d)
        self.shape = B.shape[:3]
        n_modes, ne, ng = self.shape
        d = B.shape[-1]
        # D B for the stresses of the amplitudes; B' weighted by the point's volume for the forces
        self.DB = (model.element_D(spread=1) @ B).reshape(n_modes * ne, ng * 6, d)
        self.Bt = (B * model.ops.sample_weights[None, :, :, None, None]).reshape(n_modes * ne, ng * 6, d).transpose(0, 2, 1).copy()
        self.G = element_scatter(model)
        self.Gt = self.G.T.tocsr()
        self.point_shape = (6, ne, ng, len(self.x3))

    def unfolded(self, values: np.ndarray, rows: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """The points over the whole period and a point array (..., n_x3) on them; ``rows``:
        the array is stress rows first, (6, ..., n_x3), whose psi3 rows change sign on mirror
        images."""
        full, index, mirrored = self.images
        out = values[..., index]
        if rows:
            out[ROWS[1]] *= np.where(mirrored, -1.0, 1.0)
        return full, out

    def amplitudes(self, u: np.ndarray) -> np.ndarray:
        """``D B u`` of stacked amplitudes at the section points, rows first: (6, ne * ng, n_modes)."""
        n_modes, ne, ng = self.shape
        a = (self.DB @ (self.Gt @ u).reshape(n_modes * ne, -1, 1)).reshape(n_modes, ne * ng, 6)
        return a.transpose(2, 1, 0)

    def stress(self, u: np.ndarray) -> np.ndarray:
        """Elastic stresses (6, ne, ng, n_x3) of stacked amplitudes ``u``."""
        a = self.amplitudes(u)
        out = np.empty((6, a.shape[1], len(self.x3)))
        for t, rows in enumerate(ROWS):
            out[rows] = a[rows] @ self.psi[t]
        out = out.reshape(self.point_shape)
        return out if self.homogeneous else out * self.scale

    def forces(self, sigma: np.ndarray) -> np.ndarray:
        """Internal force amplitudes (14) of all modes, stacked, of stresses at the points."""
        n_modes, ne, ng = self.shape
        projected = np.empty((6, ne * ng, n_modes))
        rows_of = sigma.reshape(6, ne * ng, -1)
        for t, rows in enumerate(ROWS):
            projected[rows] = rows_of[rows] @ self.psi_w[t]
        per_point = projected.transpose(2, 1, 0).reshape(n_modes * ne, ng * 6, 1)  # (mode and element, ng x 6)
        return self.G @ (self.Bt @ per_point).ravel()
