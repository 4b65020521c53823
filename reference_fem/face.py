"""Plane faces of a model: their nodes, outward normal and area (for walls and face probes)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skfem import FacetBasis

from cases.params import UnsupportedCase

from .frames import AXISYMMETRIC
from .model import INTORDER

#: tolerance of the planarity check, relative to the largest mesh coordinate
PLANE_TOL = 1e-9


@dataclass(frozen=True)
class PlaneFace:
    """A plane boundary face of a model's mesh.

    Attributes
    ----------
    nodes : (n,) mesh node indices on the face (vertices, edge and face midpoints)
    normal : (dim,) outward unit normal, mesh frame
    offset : ``normal . x`` of every face point (m)
    area : face area (m^2; per radian of circumference when axisymmetric)
    """

    nodes: np.ndarray
    normal: np.ndarray
    offset: float
    area: float


def plane_face(model, edge: str) -> PlaneFace:
    """The face of ``model`` on section edge ``edge``; raises UnsupportedCase if it is not plane."""
    mesh = model.rmesh.mesh
    facets = model.edge_facets(edge)
    fb = FacetBasis(mesh, model.element, facets=facets, intorder=INTORDER)
    n = np.asarray(fb.normals).reshape(model.dim, -1)
    normal = n.mean(axis=1)
    normal /= np.linalg.norm(normal)
    nodes = np.unique(model.basis.get_dofs(facets=facets).all("u^1") // model.dim)
    height = normal @ mesh.doflocs[:, nodes]
    size = np.abs(mesh.doflocs).max()
    if np.abs(n - normal[:, None]).max() > 1e-6 or np.ptp(height) > PLANE_TOL * size:
        raise UnsupportedCase(f"reference solver: edge {edge!r} is not plane (a wall or face probe needs one)")
    x = np.asarray(fb.global_coordinates())
    weight = x[0] if model.rep == AXISYMMETRIC else 1.0
    return PlaneFace(nodes, normal, float(height.mean()), float(np.sum(fb.dx * weight)))


def tangent_basis(normal: np.ndarray) -> np.ndarray:
    """Orthonormal tangents of a plane with unit ``normal``, shape ``(dim - 1, dim)``."""
    return np.linalg.svd(normal[None, :])[2][1:]
