"""The synthesized 3-D field: revolve (ring) or extrude (prism) the section mesh into hexahedra."""

from __future__ import annotations

import math

import meshio
import numpy as np

from cases.geometry import RING

from . import fourier, inhomogeneity
from .assembly import element_dofs

#: meshio's cell type per section mesh order (VTK_HEXAHEDRON = 12, VTK_TRIQUADRATIC_HEXAHEDRON = 29)
HEX_TYPE = {1: "hexahedron", 2: "hexahedron27"}
#: per section mesh order, each VTK hexahedron node's section node (in the element's node order,
#: :class:`cases.section_mesh.SectionMesh`) and station (0 bottom ... order top, along x3). Order 2 is
#: VTK's triquadratic hexahedron: the bottom and top faces' corners (0-3, 4-7) and mid-sides
#: (8-11, 12-15), the middle station's corners (16-19), its mid-sides on the faces xi = 0, xi = 1,
#: eta = 0, eta = 1 (20-23: the section's mid-sides 3-0, 1-2, 0-1, 2-3), then the bottom, top and
#: middle centres (24-26); tests/test_quad_element.py checks it against VTK's parametric coordinates
HEX_NODES = {1: (np.array([0, 1, 2, 3] * 2), np.repeat([0, 1], 4)),
             2: (np.array([0, 1, 2, 3] * 2 + [4, 5, 6, 7] * 2 + [0, 1, 2, 3] + [7, 5, 4, 6] + [8] * 3),
                 np.array([0] * 4 + [2] * 4 + [0] * 4 + [2] * 4 + [1] * 8 + [0, 2, 1]))}


def field_mesh(model, u_modes: list[np.ndarray], n_x3: int | None = None, peps: np.ndarray | None = None,
               peps_x3: np.ndarray | None = None, v_modes: list[np.ndarray] | None = None,
               relaxed: np.ndarray | None = None) -> meshio.Mesh:
    """Hexahedral 3-D mesh with the synthesized displacement (and, given ``v_modes``, velocity)
    as cartesian point data, and each cell's stress (cartesian tensor, 9 components) as cell
    data: the elastic stress of the amplitudes at the element's centre and the cell's middle
    along x3, less ``relaxed`` (the plastic strains' share, (6, n_elements, n_x3_points) at
    ``peps_x3``, from the nearest point).

    Ring: ``n_x3`` sectors around the axis (default 72); prism: ``n_x3`` slices along the span
    (default 60). A 4-node section element gives 8-node hexahedra between neighbouring
    stations along x3; a 9-node one (``mesh.order == 2``) 27-node ones (VTK's triquadratic
    hexahedron) with a station in the middle of each cell as well, so that a viewer draws the
    curved edges (:data:`HEX_NODES`). Cartesian axes as in :mod:`cases.geometry`. With ``peps``
    (the plastic strain at the sample points, (n_elements, section points, n_x3_points), at
    ``peps_x3`` along x3) each cell also carries the element's mean over its section points at
    the x3 point nearest to the cell's middle.
    ``solid`` (cell data, 0/1) is 0 in the cut-outs, whose fictitious material the field carries;
    ``region`` is each cell's index into ``case.materials`` (0: the body's material).
    """
    mesh, body = model.mesh, model.body
    ring = body == RING
    n_x3 = n_x3 or (72 if ring else 60)
    order = mesh.order
    x3 = np.linspace(0.0, 2 * math.pi if ring else model.length, order * n_x3 + (0 if ring else 1),
                     endpoint=not ring)  # the stations
    shape = (len(x3), mesh.n_nodes)
    x1, x2 = np.broadcast_to(mesh.x[:, 0], shape), np.broadcast_to(mesh.x[:, 1], shape)
    X3 = np.broadcast_to(x3[:, None], shape)
    points = np.stack([x1 * np.cos(X3), x1 * np.sin(X3), x2] if ring else [X3, x1, x2], axis=-1)
    point_data = {"displacement": _cartesian(model, u_modes, x3).reshape(-1, 3)}
    if v_modes is not None:
        point_data["velocity"] = _cartesian(model, v_modes, x3).reshape(-1, 3)
    section_node, level = HEX_NODES[order]
    # each cell's stations along x3, bottom to top: a ring's last cell closes on station 0
    stations = (order * np.arange(n_x3)[:, None] + np.arange(order + 1)) % len(x3)  # (n_x3, order + 1)
    hexes = stations[:, None, level] * mesh.n_nodes + mesh.elements[None, :, section_node]
    here, top = stations[:, 0], stations[:, -1]
    middle = x3[here] + 0.5 * ((x3[top] - x3[here]) % (2 * math.pi if ring else np.inf))
    local = _elastic_stress(model, u_modes, middle)  # (n_cells along x3, ne, 6)
    nearest = None if peps_x3 is None else np.abs(peps_x3[None, :] - middle[:, None]).argmin(axis=1)
    if relaxed is not None:
        local = local - relaxed[:, :, nearest].transpose(2, 1, 0)
    cell_data = {"stress": [_to_cartesian(model, local, middle).reshape(-1, 9)],
                 # 0 in a cut-out: fictitious material whose values a viewer masks (Threshold solid >= 1)
                 "solid": [(inhomogeneity.element_factor(model.case, mesh, middle).T == 1.0).astype(np.uint8).ravel()],
                 # the index of each cell's material in case.materials (0: the body's, then the regions')
                 "region": [np.tile(model.material_index.astype(np.int32), len(middle))]}
    if peps is not None:
        cell_data["peps"] = [peps.mean(axis=1)[:, nearest].T.ravel()]
    return meshio.Mesh(points.reshape(-1, 3), [(HEX_TYPE[order], hexes.reshape(-1, len(level)))],
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


def _elastic_stress(model, amplitudes: list[np.ndarray], x3: np.ndarray) -> np.ndarray:
    """``f D B0 u`` of the amplitudes at the element centres and ``x3``, element frame rows:
    (n_x3, n_elements, 6)."""
    mesh, body = model.mesh, model.body
    dofs = element_dofs(mesh.elements)
    out = np.zeros((len(x3), mesh.n_elements, 6))
    for s, amp in zip(model.systems, amplitudes):
        B0 = model.ops.strain(fourier.wavenumber(s.mode, body, model.length), 0.0, 0.0)  # (ne, 6, d)
        a = np.einsum(f"{'e' * (model.D.ndim - 2)}rs,esk,ek->er", model.D, B0, (s.T @ amp)[dofs], optimize=True)
        psi1, psi3 = fourier.psi(s.mode, x3, body, model.length)
        out += np.where(fourier.ROW_TYPE == 0, psi1[:, None], psi3[:, None])[:, None, :] * a[None]
    if model.case.cutouts:
        out *= inhomogeneity.element_factor(model.case, mesh, x3).T[:, :, None]
    return out


def _to_cartesian(model, local: np.ndarray, x3: np.ndarray) -> np.ndarray:
    """Voigt stresses (tensor shears) in each element's frame (t1, t2 in the section, x3),
    (n_x3, ne, 6), as cartesian tensors (n_x3, ne, 3, 3)."""
    S = np.zeros(local.shape[:2] + (3, 3))
    for k, (i, j) in enumerate(((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))):
        S[..., i, j] = S[..., j, i] = local[..., k]
    R = model.ops.rotation  # (ne, 2, 2): rows t1, t2 in the section's axes
    if model.body == RING:  # section axes r, z and the hoop direction at angle x3
        c, s = np.cos(x3)[:, None], np.sin(x3)[:, None]
        e_r = np.stack([c, s, 0 * c], axis=-1)  # (n_x3, 1, 3)
        e_z = np.broadcast_to(np.array([0.0, 0.0, 1.0]), e_r.shape)
        e_3 = np.stack([-s, c, 0 * c], axis=-1)
    else:  # x1, x2 of the section and the span x3 -> cartesian (x3, x1, x2), as the points
        e_r = np.broadcast_to(np.array([0.0, 1.0, 0.0]), (len(x3), 1, 3))
        e_z = np.broadcast_to(np.array([0.0, 0.0, 1.0]), e_r.shape)
        e_3 = np.broadcast_to(np.array([1.0, 0.0, 0.0]), e_r.shape)
    t1 = R[None, :, 0, 0, None] * e_r + R[None, :, 0, 1, None] * e_z
    t2 = R[None, :, 1, 0, None] * e_r + R[None, :, 1, 1, None] * e_z
    Q = np.stack([t1, t2, np.broadcast_to(e_3, t1.shape)], axis=-2)  # rows: the local axes, cartesian
    return np.einsum("kepi,kepq,keqj->keij", Q, S, Q, optimize=True)
