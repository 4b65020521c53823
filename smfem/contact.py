"""Contact layer (paper (17)-(19)): thin special elements between a face and a rigid wall.

One layer element sits on every segment of the face ``case.wall.edge``; its far face is the
wall (fixed). The layer is built with the same formulas as the body's elements (below); only
its elasticity ``D`` depends on the state, held at each of the layer's points (the Gauss points
along the face of every layer element, times the points along x3, the circumference) and
re-evaluated inside the iterations of a step:

* open (the layer would carry normal tension): ``D = 0``;
* stick: normal stiffness ``E_l`` and tangential stiffness ``G_l = E_l / 2``;
* slip: the tangential rows are condensed onto the normal one, ``tau = -f sigma_n d`` with the
  slip direction ``d`` (a unit vector of the two tangential shears: in the section plane and
  along x3), so the tangential stress follows Coulomb's law (18)-(19); with ``f = 0`` a closed
  point always slips. The matrix of a slipping point is the law's consistent tangent (the
  direction turns with the tangential strain, as in a return mapping), so the iterations are
  Newton's; where they still cycle they are damped (:meth:`ContactSystem.solve`).

States at the Gauss points along the face, not one at an element's centre: with the moment
scheme's gradient terms in the stiffness and the state taken at the centre, closing an element
could pull its centre open (the switch is not monotone), and a point at the edge of the contact
zone flipped between open and closed for ever (seen on the tilted wall). At the Gauss points
the layer's energy is a sum of point terms with positive weights, convex without friction.

The layer element follows the face's segments (:meth:`cases.section_mesh.SectionMesh.edge_segments`):

* 2-node segments (a 4-node body): the moment scheme's 4-node element, its points the 2 Gauss
  points along the face (:func:`moment_layer`);
* 3-node segments, corner-mid-corner (a 9-node body, ``quad9``): a 6-node element, quadratic
  along the face with the face's own functions and linear across the layer, its strain taken
  at mid-thickness at 3 Gauss points along the face, in the face's frame there
  (:func:`quadratic_layer`). 3 points, not 2: they integrate the products of the quadratics
  (times r) exactly on a straight face; 2 would leave a face pattern that no point feels.

Why not two straight 2-node facets per 3-node segment (corner-mid, mid-corner), which would
leave the layer as it is: its stiffness would not match the face it holds. A uniform closure
of linear facets loads the face 1:2:1 per segment, where a uniform traction on the quadratic
face is 1:4:1 (``int N_i ds``, the 9-node element's consistent loads). The layer is far stiffer
than the face (E_l / h = 2.1e15 Pa/m against E over a node spacing, ~4e13), so the face
settles where the two balance and the facets' pressure swings from node to node: on the rod
impact -100 ... -345 MPa along the face and the axis corner open through the whole impact
(end_uz 8 times off), where this layer gives a smooth -186 ... -228 MPa and a closed face. The
mean pressure, the rod's histories and the cost hardly differ (benchmarks/README.md). The
lumped masses do not decide it: the face is massless either way (:func:`face_free_mass`;
quad9's mid-side mass, 4 times a corner's, moves one node row in with the rest).

Only the traction rows of the layer (normal strain, the two tangential shears) carry stress:
the layer's own membrane stiffness would otherwise add a spurious tangential restraint.

The initial gap ``g`` enters as a normal pre-strain ``g / h``: the layer closes where the face
has moved ``g`` towards the wall; a tilted wall (``case.wall.slope``) gives each point its own
gap. A layer compressed beyond its thickness (the face went through the wall) and states that
cycle without settling are errors, never silent.

Harmonics: the layer's strain at a point is the sum over all modes; its stiffness couples the
modes through the state pattern along x3 (quadrature over equally spaced points, exact for the
products of the harmonics kept where the state does not change). An axisymmetric run (harmonic
0 only, uniform gap) has one point. Bodies of revolution only; the body itself must not couple
the modes (no cut-outs), so that each mode keeps its own factorization.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from cases.bodies import pair_faces
from cases.geometry import RING

from . import element, fourier, quad9
from .element import GAUSS_A, strain_operator, strain_rotation
from .fourier import Mode
from .layer_law import (
    NORMAL,
    OPEN,
    TRACTION,
    ContactError,
    LayerStates,
    layer_states,
    layer_tangent,
    offset_strain,
    slip_after,
    stick_where_reversed,
)
from .linalg import factorize_spd
from .layer_descent import descend
from .loads import region_nodes, segment_shape_functions
from .model import ModelError
from .newmark import Constants, Load, State
from .options import SolverOptions

#: the smallest share of a step towards the next iterate before a cycle counts as chattering
MIN_RELAXATION = 1.0 / 16
#: relative energy gain over a run without loads beyond which the result is rejected
ENERGY_GAIN_LIMIT = 0.01
#: an eigenvalue of a mode's face compliance below this share of its largest is a direction
#: the face cannot move in (round-off of a constraint)
RANGE_TOL = 1e-12
#: layer matrices kept per run, keyed by state (a few patterns recur)
CACHE_SIZE = 64


# -- the layer elements' geometry: points along the face, their strain operators -------------
class LayerPoints(NamedTuple):
    """The layer's points in the section, ``m`` face nodes per layer element.

    ``element`` (n_points,): the layer element (face segment) of each point; ``columns`` (m,):
    the segment's nodes in the order of ``B``'s columns; ``B`` (n_modes, n_points, 6, 3 m): the
    strain rows in the point's frame (t1 along the face, t2 across the layer, x3) of each mode
    from the face nodes' dofs (the wall's are fixed); ``weight`` (n_points,): the layer volume
    per radian each point stands for (times r); ``r`` (n_points,): its radius on the face.
    """

    element: np.ndarray
    columns: np.ndarray
    B: np.ndarray
    weight: np.ndarray
    r: np.ndarray
    #: (n_points, m): the face's shape functions at each point, on the segment's nodes in order
    N: np.ndarray
    #: the far side's nodes (its segment's, in order) of ``B``'s first columns when ``far``
    far_columns: np.ndarray


def segment_normals(x_seg: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """(n_seg, nodes, 2) unit normals of the face segments ``x_seg`` (n_seg, nodes, 2) at their
    nodes, pointing away from their elements' ``centres`` (n_seg, 2): towards the wall."""
    nodes = x_seg.shape[1]
    _, dL = segment_shape_functions(nodes, np.linspace(0.0, 1.0, nodes))  # [at node, function]
    tangent = np.einsum("jn,ena->eja", dL, x_seg)
    normal = np.stack([tangent[..., 1], -tangent[..., 0]], axis=-1)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    inward = centres - x_seg.mean(axis=1)
    return normal * -np.sign(np.einsum("eja,ea->ej", normal, inward))[..., None]


def moment_layer(x_seg: np.ndarray, wall_seg: np.ndarray, wavenumbers, far: bool = False) -> LayerPoints:
    """4-node moment-scheme layer elements on 2-node face segments (a 4-node body's face).

    Two points per element, the Gauss points along the face: the layer's stresses vary only
    along it, and ``a^2 = 1/12`` makes their mean of ``B' D B`` the moment scheme's stiffness.
    ``far``: keep the far side's columns (another body's face), else the face's only (a wall).
    """
    # xi along the face, eta from the wall to the face
    X = np.stack([wall_seg[:, 0], wall_seg[:, 1], x_seg[:, 1], x_seg[:, 0]], axis=1)
    ops = element.operators(X, RING, 0.0)
    n_e = len(x_seg)
    elements_of = np.repeat(np.arange(n_e), 2)
    xi = np.tile([-GAUSS_A, GAUSS_A], n_e)
    first = 0 if far else 6  # local nodes 0, 1: the far side; 2, 3: the face
    B = np.stack([(B0[elements_of] + xi[:, None, None] * B1[elements_of])[..., first:]
                  for B0, B1, _ in (ops.at(p) for p in wavenumbers)])
    N = np.column_stack([0.5 - xi, 0.5 + xi])  # xi runs from the face's node 0 to its node 1
    r = np.einsum("pn,pn->p", N, x_seg[elements_of, :, 0])
    return LayerPoints(elements_of, np.array([1, 0]), B, 0.5 * ops.sqrt_g[elements_of], r, N, np.array([0, 1]))


def layer6_shape_functions(xi, eta):
    """6-node layer element, quadratic along the face (``xi``), linear across the layer
    (``eta``): ``N (.., 6)``, ``dN/dxi``, ``dN/deta``, the wall's 3 nodes (eta = -1/2) first."""
    L, dL = quad9.lagrange_1d(xi)
    eta = np.asarray(eta)[..., None]
    wall, face = 0.5 - eta, 0.5 + eta
    return (np.concatenate([L * wall, L * face], axis=-1),
            np.concatenate([dL * wall, dL * face], axis=-1),
            np.concatenate([-L, L], axis=-1))


def quadratic_layer(x_seg: np.ndarray, wall_seg: np.ndarray, wavenumbers, far: bool = False) -> LayerPoints:
    """6-node layer elements on 3-node face segments (a 9-node body's face): the face's own
    quadratic interpolation, linear across the layer, its strain taken at mid-thickness at the 3
    Gauss points along the face (exact for the products of quadratics on a straight face; 2
    points would leave a face pattern that no point feels) in the frame of the face there."""
    X = np.concatenate([wall_seg, x_seg], axis=1)  # (n_seg, 6, 2)
    n_e, n_g = len(x_seg), len(quad9.GAUSS_1D)
    first = 0 if far else 9  # the far side's 3 nodes, then the face's
    B, weight, r, N_face = [], [], [], []
    for g, xi in enumerate(quad9.GAUSS_1D):
        N, dxi, deta = layer6_shape_functions(xi, 0.0)
        t1, t2 = np.einsum("i,eia->ea", dxi, X), np.einsum("i,eia->ea", deta, X)
        along = t1 / np.linalg.norm(t1, axis=1, keepdims=True)
        across = np.column_stack([-along[:, 1], along[:, 0]])
        frame = strain_rotation(np.stack([along, across], axis=1))
        strains = (strain_operator(X, RING, p, xi, 0.0, layer6_shape_functions) for p in wavenumbers)
        B.append([np.einsum("ers,esk->erk", frame, b)[..., first:] for b in strains])
        area = np.abs(t1[:, 0] * t2[:, 1] - t1[:, 1] * t2[:, 0])
        weight.append(area * (X[:, :, 0] @ N) * quad9.WEIGHTS_1D[g])
        L = quad9.lagrange_1d(xi)[0]
        r.append(x_seg[:, :, 0] @ L)
        N_face.append(np.broadcast_to(L, (n_e, 3)))
    # points element-major, as the moment layer's: element e's at e n_g ... e n_g + n_g - 1
    B = np.stack(B, axis=2).reshape(len(wavenumbers), n_e * n_g, 6, 18 - first)
    return LayerPoints(np.repeat(np.arange(n_e), n_g), np.arange(3), B, np.stack(weight, axis=1).ravel(),
                       np.stack(r, axis=1).ravel(), np.stack(N_face, axis=1).reshape(-1, 3), np.arange(3))


class LayerSide(NamedTuple):
    """One face the layer lies on: the wall's (``other`` empty, ``across`` None) or a contact
    pair's ``edge``, with ``across`` (n_nodes,) the node of the ``other`` face across each of its
    nodes and ``gap`` (n_nodes,) the initial gap there (:func:`cases.bodies.pair_faces`)."""

    edge: str
    other: str
    friction: float
    across: np.ndarray | None = None
    gap: np.ndarray | None = None


def layer_sides(case, mesh) -> list[LayerSide]:
    """The faces of a case's contact layer: the wall's, or one per contact pair."""
    if case.wall is not None:
        return [LayerSide(case.wall.edge, "", float(case.wall.friction))]
    sides = []
    for pair in case.contacts:
        pairing = pair_faces(mesh, pair)
        across = np.full(mesh.n_nodes, -1)
        across[pairing.face] = pairing.other
        gap = np.zeros(mesh.n_nodes)
        gap[pairing.face] = pairing.gap
        sides.append(LayerSide(pair.face, pair.other, float(pair.friction), across, gap))
    return sides


class ContactLayer:
    """Layer elements on ``case.wall.edge`` of a ring model, a state at each of their points.

    Parameters
    ----------
    model : :class:`smfem.model.Model` of a body of revolution without cut-outs
    thickness : layer thickness h (length units of the case)
    stiffness : layer Young's modulus E_l
    points_per_harmonic : layer points around the circumference per harmonic kept
        (:class:`smfem.options.SolverOptions`)

    Point arrays are shaped ``(n_points, n_x3, ...)``, the Gauss points along the face of each
    layer element (:class:`LayerPoints`: 2 on a 2-node face segment, 3 on a 3-node one); face
    displacements ``(n_modes, n_F)`` over the full dofs ``F`` of the face nodes.
    """

    def __init__(self, model, thickness: float, stiffness: float, points_per_harmonic: int = 8):
        case = model.case
        if case.body != RING:
            raise ModelError(f"{case.name}: the contact layer is implemented for bodies of revolution only")
        if model.coupling:
            raise ModelError(f"{case.name}: contact with material varying along x3 (cut-outs) is not supported")
        self.model, self.h, self.E, self.G = model, float(thickness), float(stiffness), 0.5 * float(stiffness)
        if case.wall is not None and case.contacts:
            raise ModelError(f"{case.name}: a rigid wall and contact pairs in one scene are not supported yet")
        l_max = max(m.l for m in model.modes)
        if l_max == 0 and case.wall is not None and case.wall.slope:
            raise ModelError(f"{case.name}: a tilted wall (wall_slope > 0) makes the contact vary around "
                             f"the circumference: set harmonics >= 2")
        # points along x3 and the basis of every mode and strain row there
        n_x3 = 1 if l_max == 0 else points_per_harmonic * (l_max + 1)
        self.x3 = 2 * math.pi * np.arange(n_x3) / n_x3
        self.w = np.full(n_x3, 2 * math.pi / n_x3)
        self.psi = np.stack([np.where(fourier.ROW_TYPE == 0, *(v[:, None] for v in fourier.psi(m, self.x3, RING, 0.0)))
                             for m in model.modes])  # (n_modes, n_x3, 6)
        specs = layer_sides(case, model.mesh)
        sides = [self._side(spec) for spec in specs]  # (points, nodes, gap) of each
        #: the side (the wall, or a pair: :func:`layer_sides`) of every point
        self.side = np.concatenate([np.full(len(p.element), k) for k, (p, _, _) in enumerate(sides)])
        self.side_edges = [(spec.edge,) + ((spec.other,) if spec.other else ()) for spec in specs]
        counts = np.cumsum([0] + [int(p.element[-1]) + 1 for p, _, _ in sides])  # each side's face segments
        self.n_elements = int(counts[-1])
        self.element = np.concatenate([p.element + c for (p, _, _), c in zip(sides, counts)])
        self.B = np.concatenate([p.B for p, _, _ in sides], axis=1)
        nodes = np.concatenate([n for _, n, _ in sides])  # (n_points, m) in the order of B's columns
        self.gap = np.concatenate([g for _, _, g in sides])  # (n_points, n_x3)
        self.f = np.concatenate([np.full((len(p.element), 1), spec.friction) for (p, _, _), spec in zip(sides, specs)])
        #: every edge the layer lies on or against (their nodes are massless, :func:`face_free_mass`)
        self.layer_edges = tuple(e for edges in self.side_edges for e in edges)
        dofs = (3 * nodes[:, :, None] + np.arange(3)).reshape(len(nodes), -1)
        self.F = np.unique(dofs)
        self.local = np.searchsorted(self.F, dofs)  # (n_points, 3 m) positions in F
        self.C = [s.T[self.F].tocsr() for s in model.systems]  # face dofs <- reduced, per mode
        self.offsets = np.cumsum([0] + [s.T.shape[1] for s in model.systems])
        self.pre_closure = self.gap / self.h  # the gap as a normal pre-strain
        self.area = np.concatenate([p.weight for p, _, _ in sides])[:, None] * self.w[None, :]
        shape = (len(self.element), n_x3)
        self.slip_strain = np.zeros(shape + (2,))  # committed tangential slip per point
        self.states = LayerStates(np.full(shape, OPEN), np.zeros(shape + (2,)), np.zeros(shape))
        # global rows/cols of every entry of the per-element face blocks, all mode pairs
        n_modes, nF = len(model.modes), len(self.F)
        R = np.arange(n_modes)[:, None, None] * nF + self.local[None]  # (modes, n_points, 3 m)
        self._rows = R.ravel()  # position in the stacked face vector of every point's dofs
        self._scatter = (R[:, None, :, :, None] * (n_modes * nF) + R[None, :, :, None, :]).ravel()
        self.size = n_modes * nF
        # the tangent of the last states asked (:meth:`D`), and their key
        self._tangent, self._tangent_key = None, None

    def _side(self, spec: LayerSide) -> tuple[LayerPoints, np.ndarray, np.ndarray]:
        """The layer elements on one face: their points, the nodes of ``B``'s columns at each
        point (the far side's first between two bodies) and the initial gap there (n_x3 wide)."""
        mesh, x = self.model.mesh, self.model.mesh.x
        seg, owner = mesh.edge_segments(spec.edge)
        face = np.unique(seg)
        # the far side of the layer, as geometry: every face node moved by h along the face's
        # outward normal there (the mean of its segments' normals at a shared corner); its
        # dofs are the wall's (fixed) or the other body's nodes across the face
        row_of = np.full(mesh.n_nodes, -1)
        row_of[face] = np.arange(len(face))
        position = row_of[seg]  # (n_seg, nodes per segment): each segment node's place in face
        normal = segment_normals(x[seg], mesh.element_x()[owner].mean(axis=1))
        out_node = np.zeros((len(face), 2))
        np.add.at(out_node, position, normal)
        out_node /= np.linalg.norm(out_node, axis=1, keepdims=True)
        far_x = x[face] + self.h * out_node
        build = moment_layer if mesh.order == 1 else quadratic_layer
        paired = spec.across is not None
        points = build(x[seg], far_x[position], [float(m.l) for m in self.model.modes], far=paired)
        nodes = seg[points.element][:, points.columns]
        if paired:  # the other body's nodes across the face's, then the face's
            nodes = np.concatenate([spec.across[seg[points.element]][:, points.far_columns], nodes], axis=1)
            gap = np.einsum("pn,pn->p", points.N, spec.gap[seg[points.element]])[:, None] + 0.0 * self.x3[None, :]
        else:
            gap = self.model.case.wall.gap_at(points.r[:, None] * np.cos(self.x3)[None, :], x[face, 0].max())
        return points, nodes, gap

    # -- kinematics ---------------------------------------------------------------------------
    def face_values(self, u: np.ndarray) -> np.ndarray:
        """(n_modes, n_F) face displacements of the stacked reduced amplitudes ``u``."""
        return np.stack([C @ u[a:b] for C, a, b in zip(self.C, self.offsets[:-1], self.offsets[1:])])

    def strain(self, u: np.ndarray) -> np.ndarray:
        """(n_points, n_x3, 6) layer strain at the layer's points."""
        return self.face_strain(self.face_values(u))

    def face_strain(self, w: np.ndarray) -> np.ndarray:
        """(n_points, n_x3, 6) layer strain of the face displacements ``w`` (n_modes, n_F)."""
        amp = np.einsum("ierk,iek->ier", self.B, w[:, self.local])
        return np.einsum("iqr,ier->eqr", self.psi, amp)

    # -- constitutive state (the law: :func:`layer_states`, :func:`layer_tangent`) -------------
    def states_of(self, strain: np.ndarray) -> LayerStates:
        """State of every point for a strain (the committed slip taken into account)."""
        return layer_states(strain, self.pre_closure, self.slip_strain, self.E, self.G, self.f)

    def D(self, states: LayerStates) -> np.ndarray:
        """The states' tangent, kept for the last states asked (a step asks for the same ones
        for its stresses and its matrix: the rod impact's 1810 tangents were 0.09 of its 0.44
        CPU s); callers do not write into it."""
        key = states.key()
        if key != self._tangent_key:
            self._tangent, self._tangent_key = layer_tangent(states, self.E, self.G, self.f), key
        return self._tangent

    def offset_strain(self, states: LayerStates) -> np.ndarray:
        return offset_strain(states, self.pre_closure, self.slip_strain)

    def stress(self, strain: np.ndarray, states: LayerStates) -> np.ndarray:
        return np.einsum("eqrs,eqs->eqr", self.D(states), strain + self.offset_strain(states))

    # -- matrices and forces ------------------------------------------------------------------
    def face_matrix(self, states: LayerStates | None, D: np.ndarray | None = None) -> np.ndarray:
        """Dense layer stiffness on the face dofs of all modes, ``(n_modes n_F)`` square, of the
        states' tangent or of the points' tangents ``D`` (n_points, n_x3, 6, 6)."""
        D = (self.D(states) if D is None else D)[..., TRACTION, :][..., TRACTION] * self.area[..., None, None]
        psi, n_modes = self.psi[..., TRACTION], len(self.C)
        Dw = np.zeros((n_modes, n_modes, len(self.element), 3, 3))
        for r in range(3):
            for s in range(3):
                if D[..., r, s].any():  # x3 quadrature as one matrix product per row pair
                    Dw[:, :, :, r, s] = ((psi[:, None, :, r] * D[None, :, :, r, s]) @ psi[:, :, s].T).transpose(0, 2, 1)
        B = self.B[:, :, TRACTION]
        k = np.einsum("ierk,ijers,jesl->ijekl", B, Dw, B, optimize=True)
        return np.bincount(self._scatter, k.ravel(), minlength=self.size**2).reshape(self.size, self.size)

    def offset_force(self, states: LayerStates) -> np.ndarray:
        """(n_modes, n_F) nodal forces of the offset strain on the face dofs, ``int B' D e_off``."""
        return self.face_force(self.stress(np.zeros(states.kind.shape + (6,)), states))

    def face_force(self, sigma: np.ndarray) -> np.ndarray:
        """(n_modes, n_F) nodal forces ``int B' sigma`` of the points' stresses (n_points, n_x3, 6)."""
        sigma = sigma[..., TRACTION] * self.area[..., None]
        projected = np.einsum("iqr,eqr->ier", self.psi[..., TRACTION], sigma)
        per = np.einsum("ierk,ier->iek", self.B[:, :, TRACTION], projected)
        return np.bincount(self._rows, per.ravel(), minlength=self.size).reshape(len(self.C), len(self.F))

    def commit(self, strain: np.ndarray, states: LayerStates) -> None:
        """End of a converged step: the slip it leaves (:func:`slip_after`); the states become
        the next step's first guess."""
        self.slip_strain = slip_after(strain, states, self.stress(strain, states), self.slip_strain, self.G)
        self.states = states

    # -- what a run reports ---------------------------------------------------------------------
    def mean_normal_stress(self, strain: np.ndarray, states: LayerStates, side: int | None = None) -> float:
        """Mean normal stress on the face (compressive negative): the contact pressure; of one
        side's points (:attr:`side_edges`) or of all."""
        area = self.area if side is None else np.where((self.side == side)[:, None], self.area, 0.0)
        return float(np.sum(area * self.stress(strain, states)[..., NORMAL]) / area.sum())

    def energy(self, strain: np.ndarray, states: LayerStates) -> float:
        """Strain energy stored in the layer (the model's integrals along x3)."""
        sigma = self.stress(strain, states)
        return float(0.5 * np.einsum("eqr,eqr,eq->", sigma, strain + self.offset_strain(states), self.area))

    def closed_fraction(self, states: LayerStates) -> float:
        """Share of the face area in contact (stick or slip)."""
        return float(self.area[states.kind != OPEN].sum() / self.area.sum())


def face_free_mass(model, edge, i: int = 0) -> np.ndarray:
    """Lumped mass (3 n_nodes,) of mode ``i`` with the face nodes' mass moved to the next row in
    (``edge``: a face's name, or several: both faces of a contact pair).

    A massive face node on the stiff layer is an oscillator far above what dt resolves:
    Newmark leaves it undamped and the contact pressure rings at the Nyquist frequency. With
    massless contact nodes (mass redistribution, Khenous, Laborde & Renard 2008) the face
    follows quasi-statically; the total mass is kept.
    """
    m = model.full_mass(i, i).reshape(-1, 3).copy()
    mesh = model.mesh
    if mesh.shape is None:
        for name in (edge,) if isinstance(edge, str) else edge:
            face, inside = _next_row_in(mesh, name)
            m[inside] += m[face]
            m[face] = 0.0
        return m.ravel()
    if not isinstance(edge, str):  # a mapped block is one body: one face against the wall
        (edge,) = edge
    ns, nt = mesh.shape
    grid = np.arange(mesh.n_nodes).reshape(mesh.order * nt + 1, mesh.order * ns + 1)  # mid-sides too
    face, inside = {"s_min": (grid[:, 0], grid[:, 1]), "s_max": (grid[:, -1], grid[:, -2]),
                    "t_min": (grid[0], grid[1]), "t_max": (grid[-1], grid[-2])}[model.mesh.section.edge(edge)]
    m[inside] += m[face]
    m[face] = 0.0
    return m.ravel()


#: per order, the local node next in from each node of an element's edge k (its nodes in the
#: order of :meth:`cases.section_mesh.SectionMesh.edge_segments`), as functions of k
_ACROSS = {1: lambda k: ((k + 3) % 4, (k + 2) % 4),
           2: lambda k: (4 + (k + 3) % 4, 8, 4 + (k + 1) % 4)}


def _next_row_in(mesh, edge: str) -> tuple[np.ndarray, np.ndarray]:
    """An unstructured section's face nodes on ``edge`` and, for each, the node one row in
    across its owner element (a structured grid's next row)."""
    seg, owner = mesh.edge_segments(edge)
    local = mesh.elements[owner]  # (n_seg, nodes)
    first = np.argmax(local == seg[:, :1], axis=1)  # the segment's first corner in its element
    second = np.argmax(local == seg[:, -1:], axis=1)
    k = np.where((second - first) % 4 == 1, first, second)  # the edge k -> k + 1 the segment runs on
    reverse = k != first  # the segment runs k + 1 -> k
    across = np.array([_ACROSS[mesh.order](int(j)) for j in k])  # (n_seg, order + 1), along k -> k + 1
    across = np.where(reverse[:, None], across[:, ::-1], across)
    targets = local[np.arange(len(seg))[:, None], across]
    face, where = np.unique(seg.ravel(), return_index=True)
    return face, targets.ravel()[where]


class ContactSystem:
    """The steps of a ring model with a contact layer (a system of :func:`smfem.newmark.march`).

    Each step iterates: solve with the layer matrix of the current states, re-evaluate the
    states from the new displacements, until no state (and no slip direction) changes. Each
    mode's ``K + a0 M`` is factorized once: the layer touches only the face dofs ``F``, so
    ``(A0 + C' k C) x = b`` (``A0`` block-diagonal over the modes, ``C`` the face rows, ``k``
    the layer's dense face matrix, which couples the modes) is solved as ``x = y - Z c`` with
    ``y = A0^-1 b``, ``Z = A0^-1 C'`` (per mode, once) and the small dense system
    ``(I + k S) c = k C y``, ``S = C Z`` (Woodbury). The face nodes are massless
    (:func:`face_free_mass`).
    """

    HOW = ("contact layer (17)-(19): states per layer Gauss point and point along x3, iterated per step; "
           "one factorization per mode, the layer's face matrix by Woodbury")

    def __init__(self, model, dt: float, options: SolverOptions, terms=()):
        case = model.case
        p = case.params
        layer = self.layer = ContactLayer(model, p["layer_thickness"], p["layer_stiffness"] * case.material.E,
                                          options.layer_points_per_harmonic)
        self._velocity_rows: dict = {}
        systems = model.systems
        self.model, self.K, self.max_state_iterations = model, [s.K for s in systems], options.max_state_iterations
        #: the load: pressures held from t = 0 and the timed terms (amplitudes, moving loads, forces)
        self.load = Load(np.concatenate([s.Q for s in systems]), terms)
        self.m_full = [face_free_mass(model, layer.layer_edges, i) for i in range(len(systems))]
        self.M = np.concatenate([s.T.multiply(s.T).T @ m for s, m in zip(systems, self.m_full)])
        self.c = Constants.of(dt)
        self.offsets = layer.offsets
        self.lus = [factorize_spd(K + sp.diags(self.c.a0 * M)) for K, M in zip(self.K, self.blocks(self.M))]
        self.factorizations = len(self.lus)
        self.Z = [lu.solve(C.T.toarray()) for lu, C in zip(self.lus, layer.C)]
        nF = len(layer.F)
        self.S = np.zeros((layer.size, layer.size))
        for i, (C, Z) in enumerate(zip(layer.C, self.Z)):
            self.S[i * nF:(i + 1) * nF, i * nF:(i + 1) * nF] = C @ Z
        self.face_blocks: dict[bytes, np.ndarray] = {}
        self._S_inv: tuple[np.ndarray, np.ndarray] | None = None
        self.descents: list[int] = []  # the steps the line-search method settled
        self.max_closure = 0.0  # largest layer compression over the run, in layer thicknesses
        self.energies, self.closed, self.contact_steps, self.last = [], [0.0], [], None

    def blocks(self, vector: np.ndarray) -> list[np.ndarray]:
        """The per-mode parts of a stacked vector."""
        return [vector[a:b] for a, b in zip(self.offsets[:-1], self.offsets[1:])]

    def stiffness_product(self, u: np.ndarray) -> np.ndarray:
        """``K u`` of the body (all modes stacked)."""
        return np.concatenate([K @ ui for K, ui in zip(self.K, self.blocks(u))])

    def _mean_axial_velocity_row(self, region: str | None) -> np.ndarray:
        """Row giving the mass-weighted mean axial velocity (momentum / mass) of stacked
        amplitudes, of the whole section or of one region (a body): only harmonic 0 carries a
        mean."""
        row = np.zeros(self.model.n_dof)
        nodes = region_nodes(self.model.mesh, region)
        for i, (s, m_full) in enumerate(zip(self.model.systems, self.m_full)):
            if s.mode == Mode(0, "c"):
                axial = np.zeros((len(m_full) // 3, 3))
                axial[nodes, 1] = m_full.reshape(-1, 3)[nodes, 1]  # x2 = z is the axis of the rod
                axial = axial.ravel()
                row[self.offsets[i]:self.offsets[i + 1]] = (s.T.T @ axial) / axial.sum()
        return row

    def _solve(self, states: LayerStates, y: np.ndarray, offset: bool = True) -> np.ndarray:
        """Solution with the layer in ``states``, given ``y = A0^-1 b`` of the step's load ``b``
        (``offset``: with the layer's offset forces, else the matrix's inverse alone).

        The layer's offset forces act on the face dofs only, ``C' f``, so their response is
        ``Z f``: no back-substitution per iteration, one per mode and step."""
        f = self.layer.offset_force(states) if offset else np.zeros((len(self.Z), len(self.layer.F)))
        if (states.kind != OPEN).any():
            key = states.key()
            k = self.face_blocks.get(key)
            if k is None:
                if len(self.face_blocks) >= CACHE_SIZE:
                    self.face_blocks.clear()
                k = self.face_blocks[key] = self.layer.face_matrix(states)
            Cy = self.layer.face_values(y).ravel() - self.S @ f.ravel()
            try:
                f = f + np.linalg.solve(np.eye(len(k)) + k @ self.S, k @ Cy).reshape(f.shape)
            except np.linalg.LinAlgError:  # a layer far stiffer than round-off lets the body answer
                raise ContactError("the contact layer's face system is singular (the layer against the body "
                                   "at this step: a far stiffer layer or a far longer step)") from None
        return y - np.concatenate([Z @ fi for Z, fi in zip(self.Z, f)])

    def static_residual(self, u: np.ndarray, states: LayerStates, t: float) -> np.ndarray:
        """``Q(t) - K u`` less the layer's nodal forces in ``states`` (its tangent and offsets,
        the step's linear system): the out-of-balance force of a static solution ``u``."""
        f = self.layer.face_force(self.layer.stress(self.layer.strain(u), states))
        return self.load(t) - self.stiffness_product(u) - np.concatenate([C.T @ fi for C, fi in zip(self.layer.C, f)])

    def correction(self, states: LayerStates, r: np.ndarray) -> np.ndarray:
        """``(K + a0 M + C' k C)^-1 r``, the step's matrix with the layer's tangent in ``states``."""
        base = np.concatenate([lu.solve(ri) for lu, ri in zip(self.lus, self.blocks(r))])
        return self._solve(states, base, offset=False)

    def initial_acceleration(self, u: np.ndarray) -> np.ndarray:
        """``M a = Q - K u``; the massless face nodes carry no initial acceleration."""
        self.strain, self.states = self.layer.strain(u), self.layer.states
        force = self.load(0.0) - self.stiffness_product(u)
        return np.divide(force, self.M, out=np.zeros_like(force), where=self.M > 0)

    def solve(self, predicted: np.ndarray, u: np.ndarray, step_index: int, t: float) -> tuple[np.ndarray, int]:
        """One step's displacement and its state iterations: Newton's method on the layer's law
        (:meth:`_newton`), or where its iterates do not settle the line-search method of
        :mod:`smfem.layer_descent` from the step's start (counted in ``info``)."""
        c, layer = self.c, self.layer
        load = self.load(t) + c.a0 * self.M * predicted
        base = np.concatenate([lu.solve(r) for lu, r in zip(self.lus, self.blocks(load))])
        try:
            new, iteration, strain, states = self._newton(base, step_index, t)
        except ContactError as newton:
            try:
                new, more = descend(self, base, u, step_index, t)
            except ContactError as e:
                raise ContactError(f"{newton}; {e}") from None
            iteration = self.max_state_iterations + more
            self.descents.append(step_index)
            strain = layer.strain(new)
            states = layer.states_of(strain)
        closure = -(strain[..., NORMAL] + layer.pre_closure)
        self.max_closure = max(self.max_closure, float(closure.max()))
        if closure.max() >= 1.0:
            raise ContactError(f"step {step_index} (t = {t:.6g} s): the face went through the wall or the other body (layer "
                               f"compressed {closure.max():.3g} times its thickness): raise layer_stiffness "
                               f"or lower dt")
        self.strain, self.states = strain, states
        return new, iteration

    def _newton(self, base: np.ndarray, step_index: int, t: float):
        """Newton's method on the layer's law from the body's answer ``base`` to the step's load.

        Iterates ``x -> solve(states_of(x))`` until the states a solution was computed with are
        its own. Where that cycles (a point at the edge of the contact zone, a slip direction
        that flips), the next iterates move only a share ``omega`` of the way to the new solution,
        halved at every cycle: a damped Newton method on the piecewise linear layer law. Returns
        the solution, the iterations, its layer strain and the states it was computed with.
        """
        layer = self.layer
        states, current, omega, seen = layer.states, None, 1.0, []
        for iteration in range(1, self.max_state_iterations + 1):
            new = self._solve(states, base)
            strain = layer.strain(new)
            following = stick_where_reversed(layer.states_of(strain), states)
            if following.close_to(states):
                return new, iteration, strain, states
            seen.append(states)
            if any(following.close_to(other) for other in seen):
                if omega <= MIN_RELAXATION:
                    raise ContactError(f"step {step_index} (t = {t:.6g} s): contact states cycle without "
                                       f"settling after {iteration} iterations (state chattering)")
                omega, seen = 0.5 * omega, []
            current = new if current is None else current + omega * (new - current)
            states = following if omega == 1.0 else layer.states_of(layer.strain(current))
        raise ContactError(f"step {step_index} (t = {t:.6g} s): contact states did not settle in "
                           f"{self.max_state_iterations} iterations (state chattering)")

    def face_compliance_inverse(self) -> tuple[np.ndarray, np.ndarray]:
        """The face motions a step can make and the body's stiffness along them: ``U`` (n, r),
        orthonormal columns spanning the range of ``S`` (a supported dof, or two face dofs
        that are one reduced dof, as u_r and u_theta of harmonic 1 on the axis, take none), and
        the inverse eigenvalues ``1 / lambda`` (r,) of ``S`` along them; made once, for
        :mod:`smfem.layer_descent`."""
        if self._S_inv is None:
            n = len(self.layer.F)
            columns, inverse = [], []
            for i in range(len(self.Z)):
                lam, vec = np.linalg.eigh(self.S[i * n:(i + 1) * n, i * n:(i + 1) * n])
                keep = lam > RANGE_TOL * max(lam.max(initial=0.0), 0.0)
                block = np.zeros((len(self.S), int(keep.sum())))
                block[i * n:(i + 1) * n] = vec[:, keep]
                columns.append(block)
                inverse.append(1.0 / lam[keep])
            self._S_inv = np.hstack(columns), np.concatenate(inverse)
        return self._S_inv

    def commit(self, u: np.ndarray) -> None:
        self.layer.commit(self.strain, self.states)

    # -- what a run reports ---------------------------------------------------------------------
    def contact_pressure(self, state: State, probe=None) -> float:
        """The layer's mean normal stress on the probe's face (``edge_mean`` of sigma): the
        points of the side the face belongs to (either face of a pair)."""
        edge = getattr(probe, "edge", None)
        sides = [k for k, edges in enumerate(self.layer.side_edges) if edge in edges]
        return self.layer.mean_normal_stress(self.strain, self.states, sides[0] if sides else None)

    def mean_axial_velocity(self, state: State, probe=None) -> float:
        """Mass-weighted mean axial velocity (``body_mean`` of v), of the probe's region."""
        region = getattr(probe, "region", None)
        if region not in self._velocity_rows:
            self._velocity_rows[region] = self._mean_axial_velocity_row(region)
        return float(self._velocity_rows[region] @ state.v)

    def energy(self, state: State) -> float:
        """Kinetic + strain energy of the body and the layer (the model's integrals over x3)."""
        u, v = state.u, state.v
        body = 0.5 * v @ (self.M * v) + 0.5 * u @ self.stiffness_product(u)
        return float(body + self.layer.energy(self.strain, self.states))

    def observe(self, state: State) -> None:
        """After every state: the energy at t = 0, the closed share of the face, the contact steps."""
        if state.n == 0:
            self.energies.append(self.energy(state))
        else:
            self.closed.append(self.layer.closed_fraction(self.states))
            if self.closed[-1] > 0:
                self.contact_steps.append(state.n)
        self.last = state

    def report(self) -> tuple[str, dict]:
        """The run's verdict (``''`` or why it is rejected) and the contact facts of ``info``."""
        dt = self.c.dt
        before, after = self.energies[0], self.energy(self.last)
        gain = after / before - 1 if before > 0 else 0.0
        message = ""
        if not (self.model.case.loads or self.model.case.forces) and gain > ENERGY_GAIN_LIMIT:
            # nothing does work on the rod: energy can only stay or be dissipated by friction
            message = (f"contact created energy: +{gain:.1%} over the run (a layer too stiff for dt chatters "
                       f"unseen between steps): lower layer_stiffness or dt")
        steps = self.contact_steps
        return message, {
            "layer_elements": self.layer.n_elements, "layer_points_x3": int(self.layer.states.kind.shape[1]),
            "energy_before": before, "energy_after": after,
            "contact_window": [steps[0] * dt, steps[-1] * dt] if steps else None,
            "max_layer_compression": self.max_closure, "closed_fraction": self.closed,
            # the steps whose Newton iterates did not settle, solved by the line-search method
            "line_search_steps": self.descents}
