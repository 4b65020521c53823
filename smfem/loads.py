"""Loads and initial conditions as Fourier amplitudes of the mode basis."""

from __future__ import annotations

import numpy as np

from cases.geometry import PRISM, RING, interval_fourier

from . import quad9
from .elements import Element
from .fourier import Mode, psi_integrals, psi_squared_integrals
from .fourier import psi as psi_values
from cases.section_mesh import SectionMesh


def edge_pressure_vector(mesh: SectionMesh, edge: str, body: str) -> np.ndarray:
    """Nodal forces (3 n_nodes,) of a unit pressure on ``edge``, per unit of the x3 integral.

    ``int N_i p n ds`` (a ring's times r) by Gauss-Legendre quadrature along every segment
    (:func:`_edge_points`), with ``n ds`` the tangent turned inwards: exact for straight 2-node
    segments and for curved 3-node ones (a polynomial of degree 5 at most).
    """
    x, weight, N, seg, tangent, owner = _edge_points(mesh, body, edge, with_tangent=True)
    normal = np.stack([tangent[..., 1], -tangent[..., 0]], axis=-1)  # (ns, ng, 2), times ds / dparameter
    inward = mesh.x[mesh.elements[owner, :4]].mean(axis=1) - mesh.x[seg].mean(axis=1)
    normal *= np.sign(np.einsum("ea,ea->e", normal.sum(axis=1), inward))[:, None, None]  # pressure pushes inwards
    f = np.zeros((mesh.n_nodes, 3))
    np.add.at(f[:, :2], seg, np.einsum("sg,ga,sgd->sad", weight, N, normal))
    return f.ravel()


def pressure_x3_amplitude(load, mode: Mode, body: str, length: float) -> float:
    """``int q(x3) psi1(x3) dx3`` of a pressure for one mode (exact)."""
    if load.mode is not None:
        return load.q * psi_squared_integrals(mode, body, length)[0] if mode.l == load.mode else 0.0
    return load.q * interval_fourier(load.x3_intervals, mode.l, psi1_family(mode, body), body, length)


def psi1_family(mode: Mode, body: str) -> str:
    """The family of a mode's in-plane basis function ``psi1`` along x3: a prism's is the sine."""
    return "sin" if (body == PRISM or mode.family == "s") else "cos"


def load_amplitudes(case, mesh: SectionMesh, modes: list[Mode]) -> dict[Mode, np.ndarray]:
    """Full nodal load amplitude (3 n_nodes,) of every mode of the pressures held from t = 0
    (those without an amplitude that stay in place; the others are :func:`timed_loads`)."""
    held = [load for load in case.loads if not load.timed]
    shapes = {load.edge: edge_pressure_vector(mesh, load.edge, case.body) for load in held}
    out = {}
    for mode in modes:
        Q = np.zeros(3 * mesh.n_nodes)
        for load in held:
            Q += pressure_x3_amplitude(load, mode, case.body, case.length) * shapes[load.edge]
        out[mode] = Q
    return out


class TimedLoad:
    """A load whose share of each mode varies in time: ``factors_of(modes)(t)[i] * shapes[modes[i]]``.

    A force term or a pressure with an amplitude keeps its place: one factor, ``g(t)``, for
    every mode. A moving pressure's share of mode m is ``g(t) int q psi1_m`` over the intervals
    it covers at t, exact (:func:`cases.geometry.interval_fourier`), with ``shapes`` the unit
    pressure's nodal vector.
    """

    def __init__(self, shapes: dict[Mode, np.ndarray], factor, pressure=None, body: str = "", length: float = 0.0):
        self.shapes, self.factor, self.pressure, self.body, self.length = shapes, factor, pressure, body, length

    def factors_of(self, modes: list[Mode]):
        """``t -> factors`` (len(modes),) at time t: the modes' harmonic numbers and families
        taken once, not at every step."""
        if self.pressure is None:
            return lambda t: np.full(len(modes), float(self.factor(t)))
        l = np.array([m.l for m in modes])
        sine = np.array([psi1_family(m, self.body) == "sin" for m in modes])
        q, body, length = self.pressure.q, self.body, self.length

        def at(t: float) -> np.ndarray:
            ends = self.pressure.ends_at(t, body, length)
            cos, sin = (interval_fourier(ends, l, family, body, length) for family in ("cos", "sin"))
            return float(self.factor(t)) * q * np.where(sine, sin, cos)
        return at

    def largest(self, modes: list[Mode], times: np.ndarray) -> np.ndarray:
        """Per mode, the largest magnitude of its load at ``times`` (which modes a load reaches)."""
        at = self.factors_of(modes)
        peak = np.abs(np.array([at(t) for t in times])).max(axis=0)
        return peak * np.array([np.abs(self.shapes[m]).max() for m in modes])


def timed_loads(case, mesh: SectionMesh, modes: list[Mode], element: Element) -> list[TimedLoad]:
    """The case's force terms, then its timed pressures, as :class:`TimedLoad`."""
    from cases.histories import time_factor

    out = [TimedLoad(amps, time_factor(term)) for term, amps in zip(case.forces, force_amplitudes(case, mesh, modes, element))]
    for load in case.loads:
        if not load.timed:
            continue
        shape = edge_pressure_vector(mesh, load.edge, case.body)
        if load.moving:
            out.append(TimedLoad({m: shape for m in modes}, time_factor(load), load, case.body, case.length))
        else:
            out.append(TimedLoad({m: pressure_x3_amplitude(load, m, case.body, case.length) * shape for m in modes},
                                 time_factor(load)))
    return out


def sample_times(case) -> np.ndarray:
    """Times over the window at which a timed load is looked at to find the modes it reaches:
    evenly spaced, the loads' kinks and each side of them."""
    times = set(np.linspace(0.0, case.t_end, 513).tolist())
    for load in case.loads:
        for t in load.times_of_change(case.body, case.length, case.t_end):
            times |= {t, t * (1 - 1e-6), t * (1 + 1e-6)}
    return np.array(sorted(times))


def region_nodes(mesh: SectionMesh, region: str | None):
    """The nodes of a named region's elements (a body of a scene of several), or every node."""
    return slice(None) if region is None else np.unique(mesh.elements[mesh.regions[region]])


def velocity_amplitudes(case, mesh: SectionMesh, modes: list[Mode]) -> dict[Mode, np.ndarray]:
    """Initial velocity amplitudes (3 n_nodes,): the projection ``int v psi / int psi^2`` of a
    uniform velocity (of the whole section or of one region) on each mode."""
    out = {}
    for mode in modes:
        V = np.zeros((mesh.n_nodes, 3))
        integral = psi_integrals(mode, case.body, case.length)
        norm = psi_squared_integrals(mode, case.body, case.length)
        for iv in case.initial_velocity:
            c = iv.component - 1
            which = 0 if c < 2 else 1
            if norm[which]:
                V[region_nodes(mesh, iv.region), c] += iv.value * integral[which] / norm[which]
        out[mode] = V.ravel()
    return out


#: Gauss-Legendre points per element direction for a body force over the section (exact for
#: the bilinear map times a smooth force to well below the element's own error)
SECTION_POINTS = 3


def force_amplitudes(case, mesh: SectionMesh, modes: list[Mode], element: Element) -> list[dict[Mode, np.ndarray]]:
    """Per force term of the case, the nodal load amplitude (3 n_nodes,) of every mode:
    ``int int f(x) N_i psi(x3) dA dx3`` over the section (a body force) or ``ds dx3`` along its
    edge (a traction); a ring's area element carries r. Gauss-Legendre quadrature over each
    element (``element``'s shape functions) or edge segment and along x3."""
    if not case.forces:
        return []
    from cases.manufactured import numeric  # sympy: only where there is a force to evaluate

    # along x3: enough points for the force's and the modes' variation (checked by doubling in the tests)
    period = 2 * np.pi if case.body == RING else case.length
    t3, w3 = np.polynomial.legendre.leggauss(4 * case.harmonics + 64)
    x3, w3 = 0.5 * period * (t3 + 1), 0.5 * period * w3
    psi = {m: psi_values(m, x3, case.body, case.length) for m in modes}
    out = []
    for term in case.forces:
        x, weight, N, nodes = section_points(mesh, case.body, element) if term.edge is None else _edge_points(mesh, case.body, term.edge)
        f = [numeric(c)(x[..., 0, None], x[..., 1, None], x3[None, None, :], 0.0) for c in term.pattern]  # (n, ng, n3)
        amps = {}
        for m in modes:
            F = np.zeros((mesh.n_nodes, 3))
            for c in range(3):
                along = f[c] @ (psi[m][0 if c < 2 else 1] * w3)  # (n, ng)
                np.add.at(F[:, c], nodes, np.einsum("eg,ga->ea", along * weight, N))
            amps[m] = F.ravel()
        out.append(amps)
    return out


def section_points(mesh: SectionMesh, body: str, element: Element):
    """Quadrature over every element: points (ne, ng, 2), weights (ne, ng; a ring's times r),
    shape functions (ng, nodes) and the elements' nodes."""
    g, gw = np.polynomial.legendre.leggauss(SECTION_POINTS)
    xi, eta = np.meshgrid(0.5 * g, 0.5 * g, indexing="ij")
    w2 = np.outer(0.5 * gw, 0.5 * gw).ravel()
    N, dxi, deta = element.shape_functions(xi.ravel(), eta.ravel())  # (ng, nodes)
    X = mesh.element_x()  # (ne, nodes, 2)
    x = np.einsum("ga,ead->egd", N, X)
    jac = np.abs(np.einsum("ga,ea->eg", dxi, X[..., 0]) * np.einsum("ga,ea->eg", deta, X[..., 1])
                 - np.einsum("ga,ea->eg", deta, X[..., 0]) * np.einsum("ga,ea->eg", dxi, X[..., 1]))
    return x, jac * w2 * (x[..., 0] if body == RING else 1.0), N, mesh.elements


def segment_shape_functions(nodes: int, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lagrange functions (ng, nodes) of a segment's equally spaced nodes at ``s`` in [0, 1],
    and their derivatives along s."""
    if nodes == 2:
        return np.column_stack([1 - s, s]), np.tile([-1.0, 1.0], (len(s), 1))
    return quad9.lagrange_1d(s - 0.5)


def _edge_points(mesh: SectionMesh, body: str, edge: str, with_tangent: bool = False):
    """Quadrature along every segment of a section edge: points (ns, ng, 2), weights (ns, ng;
    ``ds`` times a ring's r), the segment's shape functions (ng, nodes) and its nodes;
    ``with_tangent``: also ``dx / dparameter`` (ns, ng, 2) and the element each segment is of."""
    g, gw = np.polynomial.legendre.leggauss(SECTION_POINTS)
    s, w = 0.5 * (g + 1), 0.5 * gw
    seg, owner = mesh.edge_segments(edge)
    N, dN = segment_shape_functions(seg.shape[1], s)  # (ng, nodes)
    X = mesh.x[seg]  # (ns, nodes, 2)
    x, tangent = np.einsum("ga,sad->sgd", N, X), np.einsum("ga,sad->sgd", dN, X)
    weight = w[None, :] * (x[..., 0] if body == RING else 1.0)
    if with_tangent:
        return x, weight, N, seg, tangent, owner
    return x, weight * np.linalg.norm(tangent, axis=-1), N, seg
