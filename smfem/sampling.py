"""Stress sample points of the nonlinear solver: strain synthesis and internal forces.

Stresses live at the element's sample points in the section (the moment scheme: its 2 x 2
Gauss points, :mod:`smfem.element`) times the points of :func:`smfem.inhomogeneity.x3_rule`
along x3 on the pieces between cut-out edges (transplanted Gauss-Legendre). The section
points integrate the element's stiffness exactly (:mod:`smfem.elements`) and the x3 rule the
products of the kept modes, so the internal
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
from .assembly import element_dofs, node_dofs
from .elements import DOFS_PER_NODE
from .linalg import block_diagonal


def carried_dofs(model, nodes: np.ndarray | None = None) -> np.ndarray:
    """Full dofs of ``nodes`` (all: None) that some mode carries, sorted."""
    dofs = np.arange(DOFS_PER_NODE * model.mesh.n_nodes) if nodes is None else node_dofs(nodes).ravel()
    carried = np.zeros(DOFS_PER_NODE * model.mesh.n_nodes, bool)
    for T in {id(s.T): s.T for s in model.systems}.values():  # modes share maps
        carried[T.nonzero()[0]] = True
    return dofs[carried[dofs]]


def rows_of(model, dofs: np.ndarray) -> list[sp.csr_matrix]:
    """Each mode's map restricted to the full ``dofs``: (len(dofs), mode's amplitudes), reduced
    amplitudes -> those dofs; modes that share a map share it."""
    rows = {}
    for s in model.systems:
        if id(s.T) not in rows:
            rows[id(s.T)] = sp.csr_matrix(s.T[dofs])
    return [rows[id(s.T)] for s in model.systems]


def linear_parts(ops) -> tuple[np.ndarray, np.ndarray]:
    """``(Ba, Bb)`` (ne, ng, 6, d), ``at_samples(p) = Ba + p Bb``, checked to pair a strain row
    with dofs of its own basis type along x3 in ``Ba`` and of the other type in ``Bb`` (the
    form :class:`DofSeries` needs)."""
    Ba, Bb = ops.sample_linear_parts()
    comp_type = (np.arange(Ba.shape[-1]) % DOFS_PER_NODE == 2).astype(int)
    linked = fourier.ROW_TYPE[:, None] != comp_type[None, :]
    if np.any(Ba[..., linked]) or np.any(Bb[..., ~linked]):
        raise ValueError("a strain row mixes basis types along x3: no form per dof along x3")
    return Ba, Bb


class DofSeries:
    """Stacked mode amplitudes as two series along x3 per section dof, and the transpose.

    The strain of mode ``m`` at a section sample point is ``(Ba + k_m Bb) u_m`` (:func:`linear_parts`),
    where ``Ba`` pairs a strain row only with dofs of the row's own basis type along x3 and
    ``Bb`` only with those of the other type (:data:`smfem.fourier.ROW_TYPE`; a dof of an in-plane
    component goes as psi1, of the x3 component as psi3). So the strains of all modes at a point
    ``x3`` are ``Ba U(x3) + Bb W(x3)``, with per dof ``j`` of basis type ``c``

        U_j = sum_m psi_c^m(x3) u_mj,    W_j = sum_m k_m psi_(1-c)^m(x3) u_mj:

    the products along x3 (modes times points) act on two rows per dof instead of six stress
    rows per section sample point (on a large mesh of 4-node elements a quarter). The rows are
    sorted by basis type, one matrix product per type; :attr:`row` says where each series is.
    The products are dense on purpose: at nonuniform points along x3 nonuniform FFTs
    (FINUFFT, O(H log H)) lose to them up to about 1400 harmonics on this project's scenes
    (measured, ``benchmarks/x3_sampling.py`` and its table in ``benchmarks/README.md``).

    Parameters
    ----------
    model : the :class:`smfem.model.Model` whose stacked amplitudes these are
    dofs : (n,) full dofs, sorted, that some mode carries (:func:`carried_dofs`)
    x3 : (nq,) points along x3
    weights : (nq,) the points' weights in :meth:`project`
    combine : (nq, r) optional: the series at ``r`` linear combinations of the points instead
        (and ``weights`` then of the combinations)
    """

    def __init__(self, model, dofs: np.ndarray, x3: np.ndarray, weights: np.ndarray,
                 combine: np.ndarray | None = None):
        S = model.systems
        self.n_modes, self.n_dof = len(S), len(dofs)
        self.k = np.array([fourier.wavenumber(s.mode, model.body, model.length) for s in S])
        comp_type = (dofs % DOFS_PER_NODE == 2).astype(int)
        row_type = np.concatenate([comp_type, 1 - comp_type])  # U rows, then W rows
        #: the series (U_j: j, W_j: n + j) of each sorted row
        self.source = np.argsort(row_type, kind="stable")
        #: the sorted row of each series (U_j: j, W_j: n + j)
        self.row = np.argsort(self.source)
        n_first = int(np.sum(row_type == 0))
        self.types = (slice(0, n_first), slice(n_first, 2 * self.n_dof))
        psi = np.array([fourier.psi(s.mode, x3, model.body, model.length) for s in S])  # (modes, 2, nq)
        if combine is not None:
            psi = psi @ combine
        self.psi = psi.transpose(1, 0, 2).copy()  # (2, modes, nq): synthesis per basis type
        self.psi_max = np.abs(self.psi).max(axis=2)  # (2, modes): each basis function's largest magnitude
        #: the points' mirror pairs and each type's modes by parity about them, where they have one
        #: and the product is large enough to gain by it (:data:`PARITY_MIN`)
        large = self.n_modes * len(x3) >= PARITY_MIN
        self.parity = MirrorParity.of(self.psi, x3, weights) if combine is None and large else None
        self.psi_w = (psi * weights).transpose(1, 2, 0).copy()  # (2, nq, modes): weighted projection
        self.E = block_diagonal(rows_of(model, dofs))  # stacked -> (modes, dofs)
        self.Et = self.E.T.tocsr()

    def coefficients(self, u: np.ndarray) -> np.ndarray:
        """The series' coefficients per mode of stacked amplitudes ``u``: (modes, 2 n), sorted rows."""
        N = (self.E @ u).reshape(self.n_modes, self.n_dof)
        return np.concatenate([N, N * self.k[:, None]], axis=1)[:, self.source]

    def values(self, u: np.ndarray, points: np.ndarray | None = None, coefficients: np.ndarray | None = None) -> np.ndarray:
        """The series of stacked amplitudes ``u`` at the points (``points``: at these of them
        only): (2 n, nq), sorted rows; ``coefficients``: ``u``'s (:meth:`coefficients`), made already."""
        coefficients = self.coefficients(u) if coefficients is None else coefficients
        if points is None and self.parity is not None:
            return self.parity.values(coefficients, self.types, 2 * self.n_dof)
        psi = self.psi if points is None else self.psi[:, :, points]
        out = np.empty((2 * self.n_dof, psi.shape[2]))
        for t, rows in enumerate(self.types):
            out[rows] = coefficients[:, rows].T @ psi[t]
        return out

    def bound(self, coefficients: np.ndarray) -> np.ndarray:
        """(2 n,) on the sorted rows: no series of the amplitudes whose :meth:`coefficients` these
        are exceeds this in magnitude at any of the points (the sum over the modes of each
        coefficient times its basis function's largest magnitude there)."""
        coefficients = np.abs(coefficients)
        out = np.empty(2 * self.n_dof)
        for t, rows in enumerate(self.types):
            out[rows] = self.psi_max[t] @ coefficients[:, rows]
        return out

    def amplitudes(self, projected: np.ndarray) -> np.ndarray:
        """Stacked amplitudes of the series' projections onto each mode, (2 n, modes) on the
        sorted rows: ``U*`` as it is, ``W*`` times the mode's wavenumber."""
        projected = projected[self.row]
        return self.Et @ (projected[:self.n_dof].T + self.k[:, None] * projected[self.n_dof:].T).ravel()

    def project(self, duals: np.ndarray, points: np.ndarray | None = None, rows: np.ndarray | None = None) -> np.ndarray:
        """Stacked amplitudes of ``duals`` (2 n, nq) on the sorted rows: the transpose of
        :meth:`values` with the points weighted, ``sum_q w_q (psi_c^m U*_j + k_m psi_(1-c)^m W*_j)``;
        ``points``: the duals are at these points only, zero elsewhere; ``rows`` (sorted): the
        duals are these rows only, ``(len(rows), nq)``, zero elsewhere."""
        projected = np.zeros((2 * self.n_dof, self.n_modes))
        for t, span in enumerate(self.types):
            psi = self.psi_w[t] if points is None else self.psi_w[t][points]
            if rows is None:
                projected[span] = duals[span] @ psi
            else:
                lo, hi = np.searchsorted(rows, (span.start, span.stop))
                projected[rows[lo:hi]] = duals[lo:hi] @ psi
        return self.amplitudes(projected)


class MirrorParity:
    """Points along x3 symmetric about their middle, with weights to match, where every mode's
    basis function is even or odd about it (the notched moving load's points about mid-span,
    the notched cylinder's about the middle of its quarter): the series at a point and at its
    mirror image are the sums of the even modes' and of the odd modes' terms, added and
    subtracted, so the product over the modes is made at half the points.

    Attributes
    ----------
    first : the points of the first half, the middle one last where the count is odd
    second : the mirror image of each of the first ``nq // 2`` of them (a reversed slice)
    even, odd : per basis type, the modes whose function is even, odd about the middle
    psi_even, psi_odd : per basis type, those modes' functions at ``first``, (modes, nf)
    """

    def __init__(self, psi: np.ndarray, sign: np.ndarray):
        nq = psi.shape[2]
        self.first, self.second = slice(0, (nq + 1) // 2), slice(nq - 1, (nq - 1) // 2, -1)
        self.even = [np.flatnonzero(sign[t] >= 0) for t in range(2)]
        self.odd = [np.flatnonzero(sign[t] < 0) for t in range(2)]
        self.psi_even = [psi[t][self.even[t]][:, self.first].copy() for t in range(2)]
        self.psi_odd = [psi[t][self.odd[t]][:, self.first].copy() for t in range(2)]

    @classmethod
    def of(cls, psi: np.ndarray, x3: np.ndarray, weights: np.ndarray) -> "MirrorParity | None":
        """The parity of ``psi`` (2, modes, nq) about the middle of the points ``x3``, or None
        where the points, their weights or a function is not symmetric or antisymmetric there."""
        if len(x3) < 2:
            return None
        size, tiny = np.abs(x3).max(), 1e-12
        if not (np.allclose(x3[0] + x3[-1] - x3[::-1], x3, rtol=0, atol=tiny * size)
                and np.allclose(weights[::-1], weights, rtol=tiny, atol=0)):
            return None
        sign = np.sign(np.einsum("tmq,tmq->tm", psi[:, :, ::-1], psi))
        if not np.allclose(psi[:, :, ::-1], sign[:, :, None] * psi, rtol=0, atol=tiny * np.abs(psi).max()):
            return None
        return cls(psi, sign)

    def values(self, coefficients: np.ndarray, types, n_rows: int) -> np.ndarray:
        """:meth:`DofSeries.values` at every point: (n_rows, nq)."""
        half = self.psi_even[0].shape[1]
        pairs = self.second.start - self.second.stop
        out = np.empty((n_rows, half + pairs))
        for t, rows in enumerate(types):
            c = coefficients[:, rows]
            even, odd = c[self.even[t]].T @ self.psi_even[t], c[self.odd[t]].T @ self.psi_odd[t]
            block = out[rows]
            np.add(even, odd, out=block[:, self.first])
            np.subtract(even[:, :pairs], odd[:, :pairs], out=block[:, self.second])
        return out


def series_index(dofs: np.ndarray, elements: np.ndarray) -> np.ndarray:
    """(ne, 2 d) the series ``U`` (``j``) and ``W`` (``n + j``) of each element dof among ``dofs``
    (n,), and -1 for the dofs no mode carries (they have no series)."""
    local = element_dofs(elements)
    position = np.minimum(np.searchsorted(dofs, local), len(dofs) - 1)
    index = np.where(dofs[position] == local, position, -1)
    return np.concatenate([index, np.where(index >= 0, index + len(dofs), -1)], axis=1)


def section_maps(model, series: DofSeries, dofs: np.ndarray,
                 elements: np.ndarray | slice = slice(None)) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """The sparse maps between the series of ``dofs`` at a point along x3 and the stresses
    there at the sample points of ``elements``, rows ``(6, ne, ng)`` raveled: ``D (Ba U + Bb W)``,
    and the transpose of ``Ba U + Bb W`` weighted by the sample points' volumes (the forces),
    summed over the elements of each dof."""
    elements = np.arange(model.mesh.n_elements)[elements]
    Ba, Bb = linear_parts(model.ops.subset(elements))
    ne, ng, _, d = Ba.shape
    B = np.concatenate([Ba, Bb], axis=3)  # (ne, ng, 6, 2 d) on (U, W) of the element's dofs
    DB = model.element_D(elements, 1) @ B
    index = series_index(dofs, model.mesh.elements[elements])
    column = np.where(index >= 0, series.row[index], -1)
    row = np.arange(6 * ne * ng).reshape(6, ne, ng).transpose(1, 2, 0)  # (ne, ng, 6)
    keep = np.broadcast_to((column >= 0)[:, None, None, :], B.shape)
    rows = np.broadcast_to(row[..., None], B.shape)[keep]
    columns = np.broadcast_to(column[:, None, None, :], B.shape)[keep]
    shape = (6 * ne * ng, 2 * series.n_dof)
    to_stress = sp.csr_matrix((DB[keep], (rows, columns)), shape=shape)
    B = B * model.ops.sample_weights[elements][:, :, None, None]
    from_stress = sp.csr_matrix((B[keep], (columns, rows)), shape=shape[::-1])
    to_stress.eliminate_zeros(), from_stress.eliminate_zeros()
    return to_stress, from_stress


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
    ``oversampling`` times the points (:func:`smfem.inhomogeneity.x3_rule`) that integrate the
    modes' products exactly,
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


#: modes times points along x3 from which the series are made by parity (:class:`MirrorParity`):
#: the notched moving load's product at 240 harmonics (240 x 300) 0.49 -> 0.37 ms, at 480 (480 x
#: 605) 4.6 -> 3.6 ms, one thread; on the notched cylinder's 20 x 58 the split's overhead doubles it
PARITY_MIN = 20_000

#: the share of the points above which :meth:`SamplePoints.forces_at` projects whole arrays
#: (notched strip H120, 20 % of the points yielding: 0.29 s by the points, 0.19 s whole)
DENSE_SHARE = 0.05


class SamplePoints:
    """Linear maps between mode amplitudes and stresses and forces at the sample points.

    An isotropic D couples only strain rows with the same basis function along x3, so the
    elastic stress at a point is ``f D (Ba U + Bb W)`` of the series of the section's dofs
    along x3 (:class:`DofSeries`): one sparse product in the section per row of points.
    """

    def __init__(self, model, oversampling: float, at_least: int = 0):
        self.model = model
        self.x3, self.w, self.symmetry = sample_points(model, oversampling, at_least)
        self.images = self.symmetry.images(self.x3)  # fixed: fields, zones and probes map onto the points
        self.factor = inhomogeneity.element_factor(model.case, model.mesh, self.x3)  # (ne, n_x3)
        # only the elements where the factor is not 1 somewhere along x3 are scaled (a notch
        # is a few of the section's elements: moving_load_notched quad9 2 of 20)
        self.scaled = np.flatnonzero((self.factor != 1.0).any(axis=1))
        self.scale = self.factor[self.scaled][None, :, None, :]
        dofs = carried_dofs(model)
        self.series = DofSeries(model, dofs, self.x3, self.w)
        self.to_stress, self.from_stress = section_maps(model, self.series, dofs)
        self.from_stress_by_column = self.from_stress.tocsc()  # sliced by section point in forces_at
        self.point_shape = (6, model.mesh.n_elements, model.ops.sample_weights.shape[1], len(self.x3))

    def unfolded(self, values: np.ndarray, rows: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """The points over the whole period and a point array (..., n_x3) on them; ``rows``:
        the array is stress rows first, (6, ..., n_x3), whose psi3 rows change sign on mirror
        images."""
        full, index, mirrored = self.images
        out = values[..., index]
        if rows:
            out[fourier.ROW_TYPE == 1] *= np.where(mirrored, -1.0, 1.0)
        return full, out

    def stress(self, u: np.ndarray) -> np.ndarray:
        """Elastic stresses (6, ne, ng, n_x3) of stacked amplitudes ``u``."""
        out = (self.to_stress @ self.series.values(u)).reshape(self.point_shape)
        if len(self.scaled):
            out[:, self.scaled] *= self.scale
        return out

    def stress_at(self, u: np.ndarray, points: np.ndarray, coefficients: np.ndarray | None = None) -> np.ndarray:
        """:meth:`stress` of ``u`` at the flat ``points`` (k,) of the point arrays only, (6, k):
        the series at the x3 points among them only (the section's sparse rows all: slicing
        them costs more than the product); ``coefficients``: ``u``'s series', made already."""
        nq = self.point_shape[3]
        if not len(points):
            return np.zeros((6, 0))
        section, x3 = np.divmod(points, nq)
        live_x3, at_x3 = np.unique(x3, return_inverse=True)
        block = (self.to_stress @ self.series.values(u, live_x3, coefficients)).reshape(6, -1, len(live_x3))
        out = block[:, section, at_x3]
        if len(self.scaled):
            out *= self.factor[section // self.point_shape[2], x3]
        return out

    def forces(self, sigma: np.ndarray) -> np.ndarray:
        """Internal force amplitudes (14) of all modes, stacked, of stresses at the points;
        only the points along x3 where some stress is not zero are projected (the plastic
        iterations' relaxed stresses are zero wherever the body has not yielded)."""
        rows = sigma.reshape(-1, len(self.x3))
        live = np.flatnonzero(rows.any(axis=0))
        if len(live) == len(self.x3):
            return self.series.project(self.from_stress @ rows)
        return self.series.project(self.from_stress @ rows[:, live], live)

    def forces_at(self, values: np.ndarray, points: np.ndarray) -> np.ndarray:
        """:meth:`forces` of stresses ``values`` (6, k) at the flat ``points`` (k,) of the
        point arrays (indices into ``(ne, ng, n_x3)``) and zero elsewhere: only the section
        points and the x3 points among them, and the series of their elements' dofs, take part
        (a step's plastic increments are at a few points: notched cylinder 1.5 %); where they
        are many (the notched strip's hinge: 20 %), the whole arrays' products are cheaper."""
        nq, n_section = len(self.x3), self.point_shape[1] * self.point_shape[2]
        if len(points) > DENSE_SHARE * n_section * nq:
            full = np.zeros((6, n_section * nq))
            full[:, points] = values
            return self.forces(full)
        section, x3 = np.divmod(points, nq)
        live_section, at_section = np.unique(section, return_inverse=True)
        live_x3, at_x3 = np.unique(x3, return_inverse=True)
        block = np.zeros((6, len(live_section), len(live_x3)))
        block[:, at_section, at_x3] = values
        columns = (np.arange(6)[:, None] * n_section + live_section[None, :]).ravel()
        sliced = self.from_stress_by_column[:, columns]
        touched = np.unique(sliced.indices)
        duals = (sliced @ block.reshape(len(columns), len(live_x3)))[touched]
        return self.series.project(duals, live_x3, touched)
