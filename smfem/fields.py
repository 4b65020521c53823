"""The synthesized 3-D field: revolve (ring) or extrude (prism) the section mesh into hexahedra."""

from __future__ import annotations

import math

import meshio
import numpy as np

from cases.geometry import RING

from . import fourier


def field_mesh(model, u_modes: list[np.ndarray], n_x3: int | None = None, peps: np.ndarray | None = None,
               peps_x3: np.ndarray | None = None, v_modes: list[np.ndarray] | None = None) -> meshio.Mesh:
    """Hexahedral 3-D mesh with the synthesized displacement (and, given ``v_modes``, velocity)
    as cartesian point data.

    Ring: ``n_x3`` sectors around the axis (default 72); prism: ``n_x3`` slices along the span
    (default 60). Cartesian axes as in :mod:`cases.geometry`. With ``peps`` (the plastic strain
    at the sample points, (n_elements, 4, n_x3_points), at ``peps_x3`` along x3) each cell also
    carries the element's mean over its Gauss points at the x3 point nearest to the cell's middle.
    """
    mesh, body = model.mesh, model.body
    ring = body == RING
    n_x3 = n_x3 or (72 if ring else 60)
    x3 = np.linspace(0.0, 2 * math.pi if ring else model.length, n_x3 + (0 if ring else 1), endpoint=not ring)
    shape = (len(x3), mesh.n_nodes)
    x1, x2 = np.broadcast_to(mesh.x[:, 0], shape), np.broadcast_to(mesh.x[:, 1], shape)
    X3 = np.broadcast_to(x3[:, None], shape)
    if ring:
        points = np.stack([x1 * np.cos(X3), x1 * np.sin(X3), x2], axis=-1)
        nxt = (np.arange(n_x3) + 1) % n_x3
    else:
        points = np.stack([X3, x1, x2], axis=-1)
        nxt = np.arange(1, len(x3))
    point_data = {"displacement": _cartesian(model, u_modes, x3).reshape(-1, 3)}
    if v_modes is not None:
        point_data["velocity"] = _cartesian(model, v_modes, x3).reshape(-1, 3)
    here = np.arange(len(nxt))
    n = mesh.n_nodes
    e = mesh.elements
    hexes = np.concatenate([e[None] + (here * n)[:, None, None], e[None] + (nxt * n)[:, None, None]], axis=2)
    cell_data = {}
    if peps is not None:
        middle = x3[here] + 0.5 * ((x3[nxt] - x3[here]) % (2 * math.pi if ring else np.inf))
        nearest = np.abs(peps_x3[None, :] - middle[:, None]).argmin(axis=1)
        cell_data["peps"] = [peps.mean(axis=1)[:, nearest].T.ravel()]
    return meshio.Mesh(points.reshape(-1, 3), [("hexahedron", hexes.reshape(-1, 8))],
                       point_data=point_data, cell_data=cell_data)


def _cartesian(model, amplitudes: list[np.ndarray], x3: np.ndarray) -> np.ndarray:
    """The vector field of per-mode amplitudes at the section's nodes times ``x3``, cartesian:
    (n_x3, n_nodes, 3)."""
    mesh, body = model.mesh, model.body
    u = np.zeros((len(x3), mesh.n_nodes, 3))
    for s, amp in zip(model.systems, amplitudes):
        full = (s.T @ amp).reshape(-1, 3)
        psi1, psi3 = fourier.psi(s.mode, x3, body, model.length)
        u += np.einsum("k,nc->knc", psi1, full * [1, 1, 0]) + np.einsum("k,nc->knc", psi3, full * [0, 0, 1])
    if body == RING:
        c, s = np.cos(x3)[:, None], np.sin(x3)[:, None]
        return np.stack([u[..., 0] * c - u[..., 2] * s, u[..., 0] * s + u[..., 2] * c, u[..., 1]], axis=-1)
    return np.stack([u[..., 2], u[..., 0], u[..., 1]], axis=-1)
