"""Shared test helpers: small static solves and modified scenes."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.sparse.linalg as sla

from cases import get_case
from cases.geometry import RING, Axis, Pressure, Section, Support
from smfem import assembly, element, fourier
from smfem.model import Model

#: 2 x 2 Gauss points in the element's natural coordinates (-1/2 ... 1/2)
GAUSS_2 = np.array([-0.5, 0.5]) / np.sqrt(3.0)


def element_stiffness_full(X: np.ndarray, body: str, p: float, D: np.ndarray) -> np.ndarray:
    """Plain bilinear element with full 2 x 2 Gauss integration of every strain row: the
    locking-prone baseline the moment scheme is compared with (never used by the solver)."""
    k = 0.0
    for xi in GAUSS_2:
        for eta in GAUSS_2:
            N, dxi, deta = element.shape_functions(xi, eta)
            J = np.stack([np.einsum("eia,i->ea", X, dxi), np.einsum("eia,i->ea", X, deta)], axis=2)
            w = np.abs(np.linalg.det(J)) / 4.0
            if body == RING:
                w = w * np.einsum("ei,i->e", X[:, :, 0], N)
            B = element.strain_operator(X, body, p, xi, eta)
            k = k + np.einsum("eri,ers,esj->eij", B, D, B) * w[:, None, None]
    return k


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
