"""Faces of a model: their nodes, outward normal and area (for walls, contact pairs and face
probes); a plane face's one normal (:func:`plane_face`), or a curved face's at each node
(:func:`face_of`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from cases.params import UnsupportedCase

from . import ties
from .frames import AXISYMMETRIC
from .model import INTORDER

#: tolerance of the planarity check, relative to the largest mesh coordinate
PLANE_TOL = 1e-9
#: how far inside a facet (in its reference coordinates) its nodes' normals are taken on a mesh
#: degenerate on the axis
AXIS_INSET = 1e-6


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


@dataclass(frozen=True)
class Face:
    """A boundary face of a model's mesh, plane or curved.

    Attributes
    ----------
    nodes : (n,) mesh node indices on the face
    normals : (n, dim) outward unit normal at each node, mesh frame (on a plane face all one)
    area : face area (m^2; per radian of circumference when axisymmetric)
    """

    nodes: np.ndarray
    normals: np.ndarray
    area: float


def plane_face(model, edge: str) -> PlaneFace:
    """The face of ``model`` on section edge ``edge``; raises UnsupportedCase if it is not plane."""
    face = _plane(model, edge)
    if face is None:
        raise UnsupportedCase(f"reference solver: edge {edge!r} is not plane (a wall or face probe needs one)")
    return face


def _plane(model, edge: str) -> PlaneFace | None:
    """The plane face on ``edge``, or None where it is not plane."""
    mesh = model.rmesh.mesh
    facets = model.edge_facets(edge)
    fb = ties.facet_basis(mesh, model.element, facets=facets, intorder=INTORDER)
    n = np.asarray(fb.normals).reshape(model.dim, -1)
    normal = n.mean(axis=1)
    normal /= np.linalg.norm(normal)
    nodes = np.unique(model.basis.get_dofs(facets=facets).all("u^1") // model.dim)
    height = normal @ model.nodes_x[:, nodes]
    size = np.abs(model.nodes_x).max()
    if np.abs(n - normal[:, None]).max() > 1e-6 or np.ptp(height) > PLANE_TOL * size:
        return None
    return PlaneFace(nodes, normal, float(height.mean()), _area(model, fb))


def _area(model, fb) -> float:
    x = np.asarray(fb.global_coordinates())
    weight = x[0] if model.rep == AXISYMMETRIC else 1.0
    return float(np.sum(fb.dx * weight))


def face_of(model, edge: str) -> Face:
    """The face on ``edge`` with a normal at every node: a plane face's one normal
    (:func:`plane_face`), else each node's from the facets' own quadratic geometry there: the
    outward normal of every facet at its nodes, averaged over the facets that share a node (a
    node at a kink gets their bisector)."""
    plane = _plane(model, edge)
    if plane is not None:
        return Face(plane.nodes, np.broadcast_to(plane.normal, (plane.nodes.size, model.dim)), plane.area)
    mesh, dim = model.rmesh.mesh, model.dim
    facets = model.edge_facets(edge)
    # a rule whose points are the facet's own nodes: (0, 1/2, 1) along each of its directions;
    # on a mesh with hexahedra degenerate on the axis (reference_fem.ties) a hair inside them,
    # where the map's Jacobian is not singular (each point still nearest its node)
    inset = AXIS_INSET if ties.node_ids(mesh) is not None else 0.0
    line = np.array([inset, 0.5, 1.0 - inset])
    points = np.array([g.ravel() for g in np.meshgrid(*([line] * (dim - 1)), indexing="ij")])
    at_nodes = ties.facet_basis(mesh, model.element, facets=facets, quadrature=(points, np.ones(points.shape[1])))
    n = np.asarray(at_nodes.normals).reshape(dim, -1)
    x = np.asarray(at_nodes.global_coordinates()).reshape(dim, -1)
    nodes = np.unique(model.basis.get_dofs(facets=facets).all("u^1") // dim)
    # each point is one of the face's nodes (one body's: no two at one place)
    which = cKDTree(model.nodes_x[:, nodes].T).query(x.T)[1]
    normals = np.zeros((nodes.size, dim))
    np.add.at(normals, which, n.T)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    fb = ties.facet_basis(mesh, model.element, facets=facets, intorder=INTORDER)
    return Face(nodes, normals, _area(model, fb))


def tangent_basis(normal: np.ndarray) -> np.ndarray:
    """Orthonormal tangents of a plane with unit ``normal``, shape ``(dim - 1, dim)``."""
    return np.linalg.svd(normal[None, :])[2][1:]


def tangent_bases(normals: np.ndarray) -> np.ndarray:
    """:func:`tangent_basis` of each of ``normals`` (n, dim): ``(n, dim - 1, dim)``."""
    return np.linalg.svd(normals[:, None, :])[2][:, 1:]
