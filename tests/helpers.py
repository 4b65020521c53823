"""Shared test helpers: small static solves and modified scenes."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.sparse.linalg as sla

from cases import get_case
from cases.geometry import RING, Axis, Cutout, Pressure, Section, Support
from smfem import assembly, element, elements, fourier
from cases.section_mesh import section_mesh
from smfem.model import Model

class FullBilinearOperators:
    """:class:`smfem.elements.Operators` of the plain bilinear element with full 2 x 2 Gauss
    integration of every strain row: the locking-prone baseline the moment scheme is compared
    with, and the element the tests plug in through the protocol (``full4``). Its sample
    points are its Gauss points, its lumped mass the row sums ``int N_i dV``."""

    def __init__(self, X: np.ndarray, body: str):
        self.X, self.body = X, body
        self.rotation = element.local_frame(X)
        self._T = element.strain_rotation(self.rotation)
        N, dxi, deta = element.shape_functions(element.GAUSS_XI, element.GAUSS_ETA)  # (points, nodes)
        J = np.stack([np.einsum("gi,eia->ega", dxi, X), np.einsum("gi,eia->ega", deta, X)], axis=3)
        self.sample_weights = np.abs(np.linalg.det(J)) / 4.0  # (ne, points)
        if body == RING:
            self.sample_weights = self.sample_weights * np.einsum("gi,ei->eg", N, X[:, :, 0])
        self.node_volume = self.sample_weights @ N

    def subset(self, elements):
        return FullBilinearOperators(self.X[elements], self.body)

    def strain(self, p, xi, eta):
        return np.einsum("ers,esk->erk", self._T, element.strain_operator(self.X, self.body, p, xi, eta))

    def at_samples(self, p):
        return np.stack([self.strain(p, xi, eta) for xi, eta in zip(element.GAUSS_XI, element.GAUSS_ETA)], axis=1)

    def sample_linear_parts(self):
        A = self.at_samples(0.0)
        return A, self.at_samples(1.0) - A

    def stiffness(self, p, D, q=None):
        L = self.at_samples(p)
        R = L if q is None or q == p else self.at_samples(q)
        return np.einsum("eg,egri,ers,egsj->eij", self.sample_weights, L, D, R, optimize=True)


#: the fully integrated bilinear element, in smfem's table of elements
FULL4 = elements.register(elements.Element("full4", 4, element.shape_functions,
                                           lambda X, body, nu: FullBilinearOperators(X, body),
                                           element.gauss_interpolation))


def with_element(case, name: str):
    """``case`` run with the section element ``name`` (the scene parameter ``element``, set
    past the scene's choices: the tests' own elements are not offered to users)."""
    return dataclasses.replace(case, params={**case.params, "element": name})


def element_stiffness_full(X: np.ndarray, body: str, p: float, D: np.ndarray) -> np.ndarray:
    """Stiffness blocks of the fully integrated bilinear element (:class:`FullBilinearOperators`)."""
    return FullBilinearOperators(X, body).stiffness(p, D)


def full_integration_stiffness(model: Model, i: int):
    """Mode ``i``'s reduced stiffness with the fully integrated element (decoupled modes)."""
    mesh, s = model.mesh, model.systems[i]
    Dw = assembly.weighted_elasticity(model.D, model.integrals(i, i))
    p = fourier.wavenumber(s.mode, model.body, model.length)
    K = assembly.assemble(element_stiffness_full(mesh.element_x(), model.body, p, Dw), mesh.elements, mesh.n_nodes)
    return (s.T.T @ K @ s.T).tocsr()


def static_solution(case, scheme: str = "moment"):
    """Static SMFEM solution: the model and the full nodal displacements (n_nodes, 3) per mode;
    ``scheme='full'``: with the fully integrated element instead of the moment scheme."""
    model = Model(case)
    stiffness = [s.K if scheme == "moment" else full_integration_stiffness(model, i) for i, s in enumerate(model.systems)]
    return model, [(s.T @ sla.spsolve(K.tocsc(), s.Q)).reshape(-1, 3) for s, K in zip(model.systems, stiffness)]


def distorted_mesh(x1_range=(1.0, 2.0), seed=0, n=(4, 3), order=1):
    """A rectangular patch with randomly moved interior nodes: general quadrilaterals (``order``
    2: 9-node ones, mid-side nodes moved too, so their edges are curved)."""
    sec = Section("rect", s=Axis(x1_range, (n[0],)), t=Axis((0.0, 1.0), (n[1],)))
    mesh = section_mesh(sec, order=order)
    rng = np.random.default_rng(seed)
    x = mesh.x.copy()
    interior = (x[:, 0] > x1_range[0]) & (x[:, 0] < x1_range[1]) & (x[:, 1] > 0) & (x[:, 1] < 1)
    h = (x1_range[1] - x1_range[0]) / n[0] / order
    x[interior] += rng.uniform(-0.25, 0.25, (interior.sum(), 2)) * h
    return x, mesh.elements


def patch_solution(K, exact: np.ndarray, grid_shape: tuple[int, int], components: int) -> np.ndarray:
    """The patch test's solve: the boundary nodes of a structured patch (its node grid
    ``grid_shape``) keep their ``exact`` values, the first ``components`` of the interior ones
    follow from ``K u = 0``."""
    grid = np.arange(len(exact) // 3).reshape(grid_shape)
    boundary = np.zeros(grid.size, bool)
    boundary[np.concatenate([grid[0], grid[-1], grid[:, 0], grid[:, -1]])] = True
    free = np.zeros(len(exact), bool)
    for c in range(components):
        free[c::3] = ~boundary
    u = exact.copy()
    u[free] = 0.0
    u[free] = sla.spsolve(K[free][:, free].tocsc(), -(K[free] @ u))
    return u


def nearest_node(model, x1, x2) -> int:
    return int(np.argmin(np.hypot(model.mesh.x[:, 0] - x1, model.mesh.x[:, 1] - x2)))


def dome_with(thickness: float, n_thick: int = 4, n_meridian: int = 20, refine: int = 1):
    """The dome scene with another shell thickness and mesh counts."""
    from cases.dome import HALF_ANGLE_DEG, R

    case = get_case("dome", {"refine": refine})
    section = dataclasses.replace(
        case.section,
        s=Axis((R - thickness / 2, R + thickness / 2), (n_thick,)),
        t=Axis((0.0, math.radians(HALF_ANGLE_DEG)), (n_meridian,)),
    )
    return dataclasses.replace(case, section=section)


def dome_apex_static(thickness, scheme="moment", **mesh):
    """Static apex displacement u_z of the dome under its pressure."""
    from cases.dome import R

    model, (u,) = static_solution(dome_with(thickness, **mesh), scheme=scheme)
    return u[nearest_node(model, 0.0, R), 1]


def clamped_plate(h: float, a: float = 10.0, n_r: int = 20, E: float = 1e7, nu: float = 0.3):
    """Axisymmetric clamped circular plate of radius a, thickness h, unit pressure on top."""
    case = get_case("dome")
    section = Section("rect", s=Axis((0.0, a), (n_r,)), t=Axis((-h / 2, h / 2), (4,)),
                      edges={"top": "t_max", "edge": "s_max"})
    return dataclasses.replace(
        case, section=section, loads=(Pressure(1.0, "top", ((0.0, 2 * math.pi),)),),
        supports=(Support("edge", (1, 2, 3)),), material=dataclasses.replace(case.material, E=E, nu=nu),
    )


def thick_cylinder_internal_pressure(p: float = 1e6, **overrides):
    case = get_case("thick_cylinder", overrides)
    return dataclasses.replace(case, loads=(Pressure(p, "inner", ((0.0, 2 * math.pi),)),))


def turned_cutouts(case, angle: float):
    """``case`` with its cut-outs turned by ``angle`` along x3 (a ring's: both families, coupled
    across them)."""
    return dataclasses.replace(case, cutouts=tuple(
        Cutout(c.s_range, c.t_range, tuple((a + angle, b + angle) for a, b in c.x3_intervals)) for c in case.cutouts))
