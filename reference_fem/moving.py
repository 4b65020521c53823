"""A pressure patch moving along x3 on the reference model: its nodal forces at any time.

The patch covers ``load.intervals_at(t)`` (:class:`cases.geometry.Pressure`). A facet of the
loaded surface is covered whole, not at all, or in part where a patch edge crosses it; the
part is integrated exactly over the covered range of the facet's reference coordinate along x3
(x3 is affine in it on the swept meshes of :mod:`reference_fem.mesh`: a prism's span exactly, a
ring's angle to the geometry's own interpolation error). So the load moves continuously, not
facet by facet, and needs no mesh line at the patch's edges.

The integrand ``-n . v dS`` along that coordinate is a polynomial (of degree 3 on a 9-node
quadrilateral's edge, at most 7 on a 27-node hexahedron's face: the area vector is the cross
product of the map's derivatives), so each facet's load per local dof is tabulated once as the
antiderivative of its interpolant through :data:`ALONG` Gauss points, and a partly covered
facet costs two evaluations of it. Building a facet basis on each step's covered ranges instead
took 65 ms a step on the turning patches' 2D ring (7936 dofs), a thousand times the step's
own work.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from cases.geometry import RING
from cases.params import UnsupportedCase

from . import ties
from .frames import AXISYMMETRIC, x3_of

#: Gauss points across a facet (exact for the quadratic facets' integrands)
POINTS = 4
#: points along x3 through which each facet's integrand is interpolated: degree 7, exact
ALONG = 8
#: a reference-coordinate range this close to 0 or 1 is the facet's end (round-off)
SNAP = 1e-12


class MovingPressure:
    """Nodal forces ``t -> Q(t)`` (unit amplitude) of a moving pressure ``load`` on ``model``."""

    def __init__(self, model, load):
        if model.rep == AXISYMMETRIC:
            raise UnsupportedCase("reference solver: a load moving round the axis needs dim=3 (the axisymmetric "
                                  "section has no theta)")
        self.model, self.load, self.case = model, load, model.case
        self.facets = model.edge_facets(load.edge)
        self.fdim = model.dim - 1
        self.z0, self.dz, self.along = self._x3_along_facets()
        self.dofs, self.antiderivative = self._tables()
        # each facet's whole load: its antiderivative from one end to the other
        whole = self.antiderivative @ (np.polynomial.legendre.legvander(np.ones(1), ALONG)
                                       - np.polynomial.legendre.legvander(-np.ones(1), ALONG))[0]
        cols = np.broadcast_to(np.arange(self.facets.size), self.dofs.shape)
        self.columns = sp.csc_matrix((whole.T.ravel(), (self.dofs.ravel(), cols.ravel())),
                                     shape=(model.basis.N, self.facets.size))

    def _basis(self, facets, quadrature) -> FacetBasis:
        """The scalar element's facet basis (the vector function ``dim j + a`` is its function
        ``j`` along component ``a``: a third of the functions to evaluate in 3D)."""
        return ties.facet_basis(self.model.rmesh.mesh, self.model.element.elem, facets=facets,
                                quadrature=quadrature)

    def _x3_along_facets(self):
        """Per facet: x3 at its reference origin, its change along the reference coordinate it
        varies along, and which coordinate that is; refused if x3 is not affine along one."""
        X = np.hstack([np.zeros((max(self.fdim, 1), 1)), np.eye(max(self.fdim, 1))])  # origin and unit points
        x = self.model.rmesh.mesh.mapping().G(X, find=self.facets)  # (dim, nf, np), as a facet basis maps them
        x3 = x3_of(self.case, self.model.rep, x.reshape(x.shape[0], -1)).reshape(x.shape[1:])
        d = x3[:, 1:] - x3[:, :1]
        if self.case.body == RING:
            d = np.mod(d + math.pi, 2 * math.pi) - math.pi
        along = np.argmax(np.abs(d), axis=1)
        dz = d[np.arange(d.shape[0]), along]
        across = np.abs(d).sum(axis=1) - np.abs(dz)
        if np.any(across > 1e-9 * np.abs(dz).max()) or np.any(dz == 0):
            raise UnsupportedCase("reference solver: a moving load's surface must be swept along x3 (its facets' "
                                  "x3 affine along one side)")
        return x3[:, 0], dz, along

    def _rule(self, along: int, points: np.ndarray):
        """A rule on the facet's reference cell: ``points`` along coordinate ``along``, each of
        weight 1, Gauss across."""
        s, ws = points, np.ones(len(points))
        if self.fdim == 1:
            return s[None, :], ws
        g, w = np.polynomial.legendre.leggauss(POINTS)
        r, wr = 0.5 * (g + 1), 0.5 * w
        a, b = np.meshgrid(s, r, indexing="ij")
        X = np.stack([a.ravel(), b.ravel()] if along == 0 else [b.ravel(), a.ravel()])
        return X, np.outer(ws, wr).ravel()

    def _tables(self) -> tuple[np.ndarray, np.ndarray]:
        """Each facet's dofs ``(n_local, n_facets)`` and the Legendre coefficients, in ``2 s - 1``
        (``s`` its reference coordinate along x3), of the antiderivative of its unit load per local
        dof ``(n_facets, n_local, ALONG + 1)``."""
        x = np.polynomial.legendre.leggauss(ALONG)[0]
        inverse = np.linalg.inv(np.polynomial.legendre.legvander(x, ALONG - 1))  # values -> coefficients
        n_local = self.model.basis.Nbfun  # a facet basis's local dofs are its element's
        dim = self.model.dim
        dofs = np.empty((n_local, self.facets.size), int)
        anti = np.empty((self.facets.size, n_local, ALONG + 1))
        for along in np.unique(self.along):
            mine = np.flatnonzero(self.along == along)
            fb = self._basis(self.facets[mine], self._rule(int(along), 0.5 * (x + 1)))
            phi = np.stack([np.asarray(fb.basis[j][0]) for j in range(fb.Nbfun)], axis=1)  # (f, scalar, q)
            n_dx = np.asarray(fb.normals).transpose(1, 0, 2) * fb.dx[:, None]  # (f, dim, q)
            # vector function dim j + a: -phi_j n_a dS
            per_point = -(phi[:, :, None] * n_dx[:, None]).reshape(mine.size, n_local, -1)
            values = per_point.reshape(per_point.shape[:2] + (ALONG, -1)).sum(axis=-1)  # across summed
            coefficients = values @ inverse.T
            dofs[:, mine] = (dim * fb.element_dofs[:, None] + np.arange(dim)[:, None]).reshape(n_local, -1)
            anti[mine] = 0.5 * np.polynomial.legendre.legint(coefficients, axis=-1)  # ds = dx / 2
        return dofs, anti

    def coverage(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Per facet, the covered range ``[lo, hi]`` of its reference coordinate along x3 (an
        empty one: ``lo >= hi``). Two separate covered parts on one facet are refused (a patch
        or a gap narrower than a facet: refine the mesh)."""
        lo, hi = np.ones(self.dz.size), np.zeros(self.dz.size)
        for a, b in self.load.intervals_at(t, self.case.body, self.case.length):
            for shift in self._shifts(a, b):
                s1, s2 = (a + shift - self.z0) / self.dz, (b + shift - self.z0) / self.dz
                s_lo, s_hi = np.clip(np.minimum(s1, s2), 0, 1), np.clip(np.maximum(s1, s2), 0, 1)
                hit = s_hi > s_lo
                apart = hit & (hi > lo) & ((s_lo > hi + SNAP) | (s_hi < lo - SNAP))
                if apart.any():
                    raise UnsupportedCase("reference solver: two separate parts of a moving load on one facet; "
                                          "refine the mesh along x3")
                lo[hit], hi[hit] = np.minimum(lo[hit], s_lo[hit]), np.maximum(hi[hit], s_hi[hit])
        lo[lo < SNAP], hi[hi > 1 - SNAP] = 0.0, 1.0
        return lo, hi

    def _shifts(self, a: float, b: float) -> tuple[float, ...]:
        """The turns ``2 pi j`` that bring ``[a, b]`` over the facets' x3 (a prism: none)."""
        if self.case.body != RING:
            return (0.0,)
        period = 2 * math.pi  # the facets' x3 lies within (-2 pi, 4 pi)
        return tuple(period * j for j in range(math.floor((-period - b) / period), math.ceil((2 * period - a) / period) + 1))

    def __call__(self, t: float) -> np.ndarray:
        """The unit pressure's nodal forces at ``t`` (N; the case's ``q`` and amplitude not in it)."""
        lo, hi = self.coverage(t)
        whole = (lo == 0.0) & (hi == 1.0)
        Q = self.columns @ whole.astype(float)
        part = np.flatnonzero((hi > lo) & ~whole)
        if part.size:
            V = (np.polynomial.legendre.legvander(2 * hi[part] - 1, ALONG)
                 - np.polynomial.legendre.legvander(2 * lo[part] - 1, ALONG))
            np.add.at(Q, self.dofs[:, part].ravel(), np.einsum("fik,fk->if", self.antiderivative[part], V).ravel())
        return Q
