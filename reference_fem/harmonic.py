"""Fourier-harmonic model of a body homogeneous along x3: one 2D problem per harmonic.

For a ring or a prism whose material does not vary along x3, the harmonics of the displacement
(ring: ``u_r, u_z ~ cos(l theta)``, ``u_theta ~ sin(l theta)``; prism: ``u1, u2 ~ sin(k x3)``,
``u3 ~ cos(k x3)``, ``k = l pi / length``) decouple exactly, and each one is a 2D problem on
the cross-section with three amplitude components ``(U, W, V)``. This module builds those
problems with scikit-fem: quadratic quadrilaterals (``ElementQuad2``), full Gauss
integration (order 4), consistent mass, on the section block of :mod:`cases.geometry` (a
section of several materials, ``case.regions``, sums each material's integrals over its own
elements: :mod:`reference_fem.regions`). It is the reference's own discretization, with nothing
in common with the SMFEM element but the basis functions along x3 that the case's symmetry
dictates (the separation of variables is exact for such bodies); :mod:`reference_fem.modal`
integrates it exactly in time.

A harmonic's load is ``Q + sum_k Q_k f_k(t)``: ``Q`` the pressures held from t = 0, and one
:class:`LoadTerm` per pressure that varies in time: an amplitude scales its usual vector, and a
moving patch's share of harmonic ``l`` is ``q g(t)`` times the integral of the basis function
over the intervals it covers at t, times the unit pressure's vector of the edge.

A section axis marked not refinable (one element across a plane-strain width or axial length)
is one the solution does not vary along: the nodes on each line across it share their
amplitudes, which leaves a 1-D problem per harmonic (exact plane strain, since that axis's
displacement is held at zero by the case's support on ``'all'``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from skfem import CellBasis, ElementQuad2, FacetBasis, LinearForm, asm

from cases.geometry import PRISM, RING, interval_fourier
from cases.histories import time_factor
from cases.params import UnsupportedCase

from . import regions
from .frames import AXISYMMETRIC
from .mesh import Block, assemble_blocks, axis_nodes, mesh_from_points
from .model import INTORDER
from .swept import edge_facets, element_nodes, pieces, section_elements

#: components of a harmonic's amplitude vector, in dof order: U (x1), W (x2), V (x3)
N_COMP = 3


def _factors(body: str, l: int, length: float) -> tuple[float, float]:
    """x3 integrals of the squared basis functions: ``(c_first, c_second)``.

    Ring: ``int cos^2`` (U, W and the strains with cos) and ``int sin^2`` (V, the strains with
    sin) over ``[0, 2 pi)``; prism: ``length / 2`` for both."""
    if body == PRISM:
        return length / 2, length / 2
    return (2 * math.pi, 0.0) if l == 0 else (math.pi, math.pi)


def unsupported_reason(case) -> str | None:
    """Why ``case`` has no harmonic model (``None`` if it has one)."""
    if case.cutouts and case.contrast < 1.0:
        return "the material varies along x3 (cut-outs)"
    if case.wall is not None:
        return "contact with a wall is not linear"
    if case.contacts:
        return "contact between bodies is not linear"
    if case.material.plastic:
        return "plasticity couples the harmonics"
    if not case.symmetric:
        return "only the symmetric family of harmonics is built"
    if case.initial_velocity:
        return "only loads from rest are built"
    if case.forces:
        return "body forces and tractions are not built"
    bad = [p.name for p in case.probes if p.kind != "point" or p.field not in ("u", "v")]
    if bad:
        return f"probes {', '.join(bad)} are not point displacements or velocities"
    return None


@dataclass
class LoadTerm:
    """One load of a harmonic that varies in time: ``Q f(t)``.

    Attributes
    ----------
    Q : load amplitudes (N per unit of ``f``), on the free amplitudes once in a :class:`Harmonic`
    factor : ``t -> f(t)`` for an array of times (a float for a float)
    kinks : times (s, > 0) where ``f``'s slope may jump: ``f`` is smooth between them
    rate : the angular rate (rad/s) of ``f`` between kinks beyond a straight line: 0 when ``f``
        is piecewise linear (an amplitude), ``k speed`` for a moving patch
    """

    Q: np.ndarray
    factor: Callable
    kinks: tuple[float, ...] = ()
    rate: float = 0.0


@dataclass
class Harmonic:
    """One harmonic's reduced problem ``M a + K u = Q + sum_k Q_k f_k(t)`` (free amplitudes).

    Attributes
    ----------
    l : harmonic number (ring: 0, 1, ...; prism: 1, 2, ...)
    K, M : csr matrices on the free amplitudes (N/m and kg, integrated over x3)
    Q : (n,) load amplitudes (N) of the pressures held from t = 0
    P : (n_probes, n) probe rows: a probe's value is ``P @ u`` for this harmonic's share
    terms : the loads that vary in time (:class:`LoadTerm`)
    """

    l: int
    K: sp.csr_matrix
    M: sp.csr_matrix
    Q: np.ndarray
    P: np.ndarray
    terms: list[LoadTerm] = field(default_factory=list)

    def load(self, t: float) -> np.ndarray:
        """The whole load at time ``t`` (N)."""
        return self.Q + sum(float(term.factor(t)) * term.Q for term in self.terms)


class HarmonicModel:
    """The per-harmonic problems of ``case`` at its ``refine`` and ``harmonics``.

    Parameters
    ----------
    case : cases.Case, homogeneous along x3 and linear (see :func:`unsupported_reason`)
    harmonics : harmonics kept (default ``case.harmonics``): ring ``l = 0 .. n-1``, prism
        ``l = 1 .. n``; harmonics without load are skipped

    Attributes
    ----------
    probes : names of the displacement (``'u'``) and velocity (``'v'``) point probes, in the
        case's order
    fields : ``'u'`` or ``'v'`` per probe
    systems : list of :class:`Harmonic`, the loaded ones
    n_dof : free amplitudes over all harmonics kept
    """

    def __init__(self, case, harmonics: int | None = None):
        why = unsupported_reason(case)
        if why:
            raise UnsupportedCase(f"harmonic model: {case.name}: {why}")
        self.case = case
        self.probes = case.probe_names
        self.fields = [p.field for p in case.probes]
        sec = case.section
        #: a mesh section's own quadratic mesh (its named edges), else None
        self.section = None
        if sec.kind == "mesh":  # its 9-node elements as they are, split refine x refine
            self.section = section_elements(case)
            # the section's pieces (bodies) share no node (:func:`reference_fem.swept.pieces`)
            self.mesh = mesh_from_points(element_nodes(case, self.section, None), groups=pieces(self.section))
        else:
            # the regions' box limits are node lines, as in the reference's own meshes
            boxes = [r for r in case.regions if r.s_range is not None]
            s_nodes = axis_nodes(sec.s, case.mesh_scale, [v for r in boxes for v in r.s_range])
            t_nodes = axis_nodes(sec.t, case.mesh_scale, [v for r in boxes for v in r.t_range])
            self.mesh = assemble_blocks([Block((s_nodes, t_nodes), lambda p: np.array(sec.to_x(p[0], p[1])))],
                                        lambda x: np.ones(x.shape[1], bool))
        self.basis = CellBasis(self.mesh, ElementQuad2(), intorder=INTORDER)
        self.tie = self._tie()
        self._operators()
        self._edges = {}
        n = harmonics or case.harmonics
        numbers = range(n) if case.body == RING else range(1, n + 1)
        loads = {l: (self._load(l), self._terms(l)) for l in numbers}
        size = {l: _size(Q, terms, case.t_end) for l, (Q, terms) in loads.items()}
        scale = max(size.values())
        # a load below round-off of the largest (cos 3 theta on the thick cylinder's patches) is none
        self.systems = [h for h in (self._harmonic(l, *loads[l]) for l in numbers
                                    if size[l] > 1e-12 * scale) if h is not None]
        if not self.systems:
            raise UnsupportedCase(f"harmonic model: {case.name}: no harmonic carries a load")
        self.n_dof = sum(h.K.shape[0] for h in self.systems)

    # -- geometry and operators ------------------------------------------------------------
    def _tie(self) -> sp.csr_matrix:
        """Map reduced node values -> mesh node values: nodes on one line across a
        non-refinable axis share their value (identity when every axis is refinable)."""
        sec, dofs = self.case.section, self.basis.doflocs
        N = self.basis.N
        if sec.kind == "mesh" or (sec.s.refinable and sec.t.refinable):
            return sp.identity(N, format="csr")
        s, t = _section_params(sec, dofs)
        along = t if not sec.s.refinable else s  # the coordinate that varies
        if not sec.s.refinable and not sec.t.refinable:
            raise UnsupportedCase("harmonic model: a section with no refinable axis")
        key = np.round(along / (np.ptp(along) or 1.0), 9)
        _, group = np.unique(key, return_inverse=True)
        return sp.csr_matrix((np.ones(N), (np.arange(N), group)), shape=(N, group.max() + 1))

    def _operators(self) -> None:
        """Sparse value and gradient operators at the quadrature points, ``(n_qp, n_nodes)``,
        the weights ``w`` (times r for a ring), each element's material (``material_index``,
        into ``case.materials``) and ``parts``: each material with its points' weights."""
        b = self.basis
        nel, nqe = b.dx.shape
        rows = np.broadcast_to(np.arange(nel * nqe).reshape(nel, nqe), (nel, nqe))
        parts = {"phi": [], "d1": [], "d2": []}
        cols = []
        for i in range(b.Nbfun):
            f = b.basis[i][0]
            parts["phi"].append(np.asarray(f))
            parts["d1"].append(f.grad[0])
            parts["d2"].append(f.grad[1])
            cols.append(np.broadcast_to(b.element_dofs[i][:, None], (nel, nqe)))
        r = np.concatenate([rows.ravel()] * b.Nbfun)
        c = np.concatenate([x.ravel() for x in cols])
        shape = (nel * nqe, b.N)
        ops = {k: sp.csr_matrix((np.concatenate([x.ravel() for x in v]), (r, c)), shape=shape) @ self.tie
               for k, v in parts.items()}
        self.phi, self.d1, self.d2 = ops["phi"], ops["d1"], ops["d2"]
        x1 = np.asarray(b.global_coordinates())[0].ravel()
        self.x1 = x1
        self.w = b.dx.ravel() * (x1 if self.case.body == RING else 1.0)
        centres = _section_params(self.case.section, regions.element_centres(self.mesh))
        self.material_index = regions.element_index(self.case, *centres)
        points = np.repeat(self.material_index, nqe)
        # each material with the weights of its own points (the others' zero): one material's are w
        self.parts = [(m, sp.diags(self.w * (points == k))) for k, m in enumerate(self.case.materials)]

    def _strains(self, l: int):
        """Strain amplitude operators ``(n_qp, 3 n)`` of harmonic ``l`` in dof order (U, W, V):
        ``normal`` (three), ``shear_first`` and ``shear_second`` (the shears integrated with the
        first and the second x3 factor)."""
        P, D1, D2 = self.phi, self.d1, self.d2
        Z = sp.csr_matrix(P.shape)
        row = lambda u, w, v: sp.hstack([u, w, v], format="csr")
        if self.case.body == RING:
            inv_r = sp.diags(1.0 / self.x1)
            normal = [row(D1, Z, Z), row(Z, D2, Z), row(inv_r @ P, Z, l * (inv_r @ P))]
            first = [row(D2, D1, Z)]
            second = [row(-l * (inv_r @ P), Z, D1 - inv_r @ P), row(Z, -l * (inv_r @ P), D2)]
        else:
            k = l * math.pi / self.case.length
            normal = [row(D1, Z, Z), row(Z, D2, Z), row(Z, Z, -k * P)]
            first = [row(D2, D1, Z)]
            second = [row(k * P, Z, D1), row(Z, k * P, D2)]
        return normal, first, second

    # -- one harmonic ------------------------------------------------------------------------
    def _harmonic(self, l: int, Q: np.ndarray, terms: list[LoadTerm]) -> Harmonic | None:
        case = self.case
        c1, c2 = _factors(case.body, l, case.length)
        normal, first, second = self._strains(l)
        trace = normal[0] + normal[1] + normal[2]
        K, m = 0, 0
        for material, W in self.parts:  # a sum over the materials, each on its own points
            lam, mu = material.lame
            K_part = c1 * (lam * trace.T @ W @ trace + 2 * mu * sum(e.T @ W @ e for e in normal)
                           + mu * sum(g.T @ W @ g for g in first))
            if c2:
                K_part = K_part + c2 * mu * sum(g.T @ W @ g for g in second)
            K = K + K_part
            m = m + self.phi.T @ W @ self.phi * material.rho
        M = sp.block_diag([c1 * m, c1 * m, c2 * m])
        T = self._reduction(l)
        if T.shape[1] == 0:
            return None
        K, M = ((T.T @ sp.csr_matrix(A) @ T).tocsr() for A in (K, M))
        K.eliminate_zeros()
        M.eliminate_zeros()
        terms = [LoadTerm(T.T @ term.Q, term.factor, term.kinks, term.rate) for term in terms]
        return Harmonic(l, K, M, T.T @ Q, self._probe_rows(l) @ T, terms)

    def _load(self, l: int, loads=None) -> np.ndarray:
        """Load amplitudes ``(3 n,)`` for harmonic ``l`` of ``loads`` (default: the case's
        pressures held from t = 0)."""
        case = self.case
        Q = np.zeros(N_COMP * self.tie.shape[1])
        family = "cos" if case.body == RING else "sin"  # of U and W
        c1 = _factors(case.body, l, case.length)[0]
        for load in [x for x in case.loads if not x.timed] if loads is None else loads:
            if load.mode is not None:
                f = load.q * c1 if l == load.mode else 0.0
            else:
                f = load.q * interval_fourier(load.x3_intervals, l, family, case.body, case.length)
            if f == 0.0:
                continue
            Q += f * self._edge_vector(load.edge)
        return Q

    def _edge_vector(self, edge: str) -> np.ndarray:
        """``(3 n,)``: the traction ``-n`` of a unit pressure on ``edge``, per unit of its x3 integral."""
        if edge in self._edges:  # the same for every harmonic
            return self._edges[edge]
        n = self.tie.shape[1]
        Q = np.zeros(N_COMP * n)
        fb = FacetBasis(self.mesh, ElementQuad2(), facets=self._edge_facets(edge), intorder=INTORDER)
        x1 = np.asarray(fb.global_coordinates())[0]
        weight = x1 if self.case.body == RING else np.ones_like(x1)
        for comp in (0, 1):
            v = asm(_traction, fb, weight=weight, e1=float(comp == 0), e2=float(comp == 1))
            Q[comp * n:(comp + 1) * n] = self.tie.T @ v
        self._edges[edge] = Q
        return Q

    def _terms(self, l: int) -> list[LoadTerm]:
        """The case's pressures that vary in time, as :class:`LoadTerm` of harmonic ``l`` (all
        dofs). A single Fourier term (``mode``) keeps its place, as in SMFEM."""
        case, out = self.case, []
        for load in case.loads:
            if not load.timed:
                continue
            kinks = load.times_of_change(case.body, case.length, math.inf)
            if load.moving and load.mode is None:
                k = l if case.body == RING else l * math.pi / case.length
                out.append(LoadTerm(self._edge_vector(load.edge), _moving_factor(load, l, case.body, case.length),
                                    kinks, abs(k * load.speed)))
            else:
                out.append(LoadTerm(self._load(l, (load,)), time_factor(load), kinks))
        return out

    def _edge_facets(self, edge: str) -> np.ndarray:
        sec, mesh = self.case.section, self.mesh
        if sec.kind == "mesh":
            return edge_facets(self.case, AXISYMMETRIC, mesh, self.section, mesh.boundary_facets(), edge,
                               np.arange(mesh.nelements))  # the section's elements, in their order
        name = sec.edge(edge)
        axis = sec.s if name[0] == "s" else sec.t
        target = axis.span[0] if name.endswith("min") else axis.span[1]
        facets = mesh.boundary_facets()
        s, t = _section_params(sec, mesh.p[:, mesh.facets[:, facets].ravel()])
        v = (s if name[0] == "s" else t).reshape(mesh.facets.shape[0], -1)
        size = max(abs(a) for a in axis.span) or 1.0
        return facets[np.all(np.abs(v - target) < 1e-8 * size, axis=0)]

    def _reduction(self, l: int) -> sp.csr_matrix:
        """``T`` (3 n, n_free): the amplitudes of harmonic ``l`` from its free ones (:meth:`_free`),
        and on a ring's axis the conditions under which the harmonic is one motion there
        (single-valued in Cartesian components): l = 0, u_r = 0; l = 1, u_z = 0 and u_theta =
        -u_r (U cos, -U sin: the axis's lateral translation, V follows U); l >= 2, none moves."""
        n3 = N_COMP * self.tie.shape[1]
        free = self._free(l)
        T = sp.csr_matrix((np.ones(free.size), (free, np.arange(free.size))), shape=(n3, free.size))
        axis = self._axis_nodes() if self.case.body == RING and l == 1 else np.zeros(0, int)
        if axis.size:  # V = -U at each axis node: V's row takes U's column, negated
            n = self.tie.shape[1]
            column = np.full(n3, -1)
            column[free] = np.arange(free.size)
            u_col = column[axis]
            keep = u_col >= 0
            T = T + sp.csr_matrix((-np.ones(keep.sum()), (2 * n + axis[keep], u_col[keep])), shape=T.shape)
        return T.tocsr()

    def _axis_nodes(self) -> np.ndarray:
        """The reduced nodes on a ring's axis (r = 0)."""
        size = np.abs(self.basis.doflocs).max()
        return np.unique(self.tie[np.flatnonzero(np.abs(self.basis.doflocs[0]) < 1e-9 * size)].indices)

    def _free(self, l: int) -> np.ndarray:
        """Free amplitude dofs of harmonic ``l``: supports, the axis of a ring (u_r at l = 0, 1
        is held here and followed by u_theta at l = 1, :meth:`_reduction`; everything at
        l >= 2), V of l = 0."""
        case, sec = self.case, self.case.section
        n = self.tie.shape[1]
        fixed = np.zeros(N_COMP * n, bool)
        reduced_nodes = lambda mask: np.unique(self.tie[np.flatnonzero(mask)].indices)
        s, t = _section_params(sec, self.basis.doflocs)
        for support in case.supports:
            if support.edge == "all":
                nodes = np.arange(n)
            elif sec.kind == "mesh":
                on = np.zeros(self.basis.N, bool)
                on[self.basis.get_dofs(facets=self._edge_facets(support.edge)).flatten()] = True
                nodes = reduced_nodes(on)
            else:
                name = sec.edge(support.edge)
                axis = sec.s if name[0] == "s" else sec.t
                target = axis.span[0] if name.endswith("min") else axis.span[1]
                size = max(abs(a) for a in axis.span) or 1.0
                nodes = reduced_nodes(np.abs((s if name[0] == "s" else t) - target) < 1e-8 * size)
            for c in support.components:
                fixed[(c - 1) * n + nodes] = True
        if case.body == RING:
            on_axis = self._axis_nodes()
            if l == 1:  # u_theta follows u_r (held where either is supported); no u_z
                fixed[on_axis] |= fixed[2 * n + on_axis]
                fixed[2 * n + on_axis] = fixed[n + on_axis] = True
            else:
                fixed[on_axis] = True  # no radial displacement on the axis
            if l >= 2:
                fixed[n + on_axis] = fixed[2 * n + on_axis] = True
            if l == 0:
                fixed[2 * n:] = True  # the cos family's l = 0 has no hoop displacement
        return np.flatnonzero(~fixed)

    def _probe_rows(self, l: int) -> np.ndarray:
        """``(n_probes, 3 n)``: probe value per unit amplitude of harmonic ``l``."""
        case = self.case
        n = self.tie.shape[1]
        rows = np.zeros((len(case.probes), N_COMP * n))
        for k, p in enumerate(case.probes):
            x1, x2, x3 = p.point
            interp = (self.basis.probes(np.array([[x1], [x2]])) @ self.tie).toarray()[0]
            comp = p.component[0] - 1
            rows[k, comp * n:(comp + 1) * n] = interp * _psi(case, l, comp, x3)
        return rows


def _size(Q: np.ndarray, terms: list[LoadTerm], t_end: float) -> float:
    """The largest load amplitude of a harmonic over ``[0, t_end]`` (sampled), to leave out the
    harmonics whose load is round-off."""
    t = np.linspace(0.0, t_end, 1025)
    size = np.abs(Q).max()
    for term in terms:
        times = np.union1d(t, [x for x in term.kinks if x < t_end])
        size += np.abs(term.Q).max() * np.abs(term.factor(times)).max()
    return float(size)


def _moving_factor(load, l: int, body: str, length: float):
    """``t -> q g(t)`` times the x3 integral of harmonic ``l``'s basis function (U, W: ring cos,
    prism sin) over the intervals a moving pressure covers at ``t``."""
    g = time_factor(load)
    family = "cos" if body == RING else "sin"

    def factor(t):
        value = load.q * np.asarray(g(t)) * interval_fourier(load.ends_at(t, body, length), l, family, body, length)
        return float(value) if np.ndim(value) == 0 else value

    return factor


@LinearForm
def _traction(v, w):
    """Unit pressure's traction ``-n`` along ``(w.e1, w.e2)``, times ``w.weight`` (r for a ring)."""
    return -(w.n[0] * w.e1 + w.n[1] * w.e2) * v * w.weight


def _psi(case, l: int, comp: int, x3: float) -> float:
    """Basis function along x3 of component ``comp`` (0-based) of harmonic ``l`` at ``x3``."""
    if case.body == RING:
        return math.sin(l * x3) if comp == 2 else math.cos(l * x3)
    k = l * math.pi / case.length
    return math.cos(k * x3) if comp == 2 else math.sin(k * x3)


def _section_params(sec, x: np.ndarray):
    """Parametric ``(s, t)`` of section points ``x``, shape ``(2, n)``."""
    return sec.from_x(x[0], x[1])
