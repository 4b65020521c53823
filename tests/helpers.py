"""Shared test helpers: small static solves and modified scenes."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.sparse.linalg as sla

from cases import get_case
from cases.geometry import Axis, Pressure, Section, Support
from smfem.model import Model


def static_solution(case, **model_options):
    """Static SMFEM solution: the model and the full nodal displacements (n_nodes, 3) per mode."""
    model = Model(case, **model_options)
    return model, [(s.T @ sla.spsolve(s.K.tocsc(), s.Q)).reshape(-1, 3) for s in model.systems]


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
