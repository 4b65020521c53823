"""How a case's body coordinates map onto the reference meshes (the one place that says so).

A scene is meshed in one of three representations:

``'plane_strain'`` (2D)
    Ring bodies: the x-y plane of the annulus, ``theta`` measured from the x axis
    counter-clockwise; prismatic bodies: the plane (x3, x2) = (span, height). The out-of-plane
    strain is zero.
``'axisymmetric'`` (2D)
    Ring bodies with ``case.axisymmetric``: the (r, z) half-plane, r-weighted forms (every
    integral is per radian of circumference).
``'solid'`` (3D)
    Cartesian x, y, z as in :mod:`cases.geometry` (ring: x = r cos theta, y = r sin theta,
    z = z; prism: x = x3, y = x1, z = x2).

Every representation has a 3-vector *mesh frame*: the mesh coordinates followed, in 2D, by the
out-of-plane direction (z for a plane-strain ring, theta for an axisymmetric ring, x1 for a
prism). Body components (1, 2, 3) are (r, z, theta) for rings and (x1, x2, x3) for prisms.
"""

from __future__ import annotations

import numpy as np

from cases.geometry import RING

PLANE_STRAIN, AXISYMMETRIC, SOLID = "plane_strain", "axisymmetric", "solid"


def representation(case) -> str:
    """The representation that ``case.params['dim']`` (default 2) asks for."""
    if case.params.get("dim", 2) == 3:
        return SOLID
    if case.body == RING and case.axisymmetric:
        return AXISYMMETRIC
    return PLANE_STRAIN


def to_cartesian(case, rep: str, x: np.ndarray) -> np.ndarray:
    """Cartesian points, shape ``(3, n)``, of mesh points ``x``, shape ``(dim, n)``.

    2D meshes are placed in their own plane: a ring's annulus at z = 0, an axisymmetric
    section in the half-plane theta = 0 (y = 0), a prism's (span, height) plane at x1 = 0.
    """
    x = np.asarray(x, float)
    zero = np.zeros_like(x[0])
    if rep == SOLID:
        return x.copy()
    if rep == AXISYMMETRIC:
        return np.array([x[0], zero, x[1]])
    if case.body == RING:
        return np.array([x[0], x[1], zero])
    return np.array([x[0], zero, x[1]])


def mesh_frame_to_cartesian(case, rep: str) -> np.ndarray:
    """Constant 3x3 matrix taking mesh-frame vector components to cartesian ones."""
    if rep == SOLID or (rep == PLANE_STRAIN and case.body == RING):
        return np.eye(3)
    # axisymmetric (r, z, theta) at theta = 0 -> (x, z, y); prism (x3, x2, x1) -> (x, z, y)
    return np.array([[1.0, 0, 0], [0, 0, 1], [0, 1, 0]])


def body_rotation(case, rep: str, x: np.ndarray) -> np.ndarray:
    """Rotations taking mesh-frame components to body components, shape ``(n, 3, 3)``.

    ``x`` are mesh points, shape ``(dim, n)``. Ring: (r, z, theta) with theta positive
    counter-clockwise about z; prism: (x1, x2, x3).
    """
    xc = to_cartesian(case, rep, x)
    n = xc.shape[1]
    if case.body == RING:
        theta = np.arctan2(xc[1], xc[0])
        c, s = np.cos(theta), np.sin(theta)
        one, zero = np.ones(n), np.zeros(n)
        cart_to_body = np.array([[c, s, zero], [zero, zero, one], [-s, c, zero]]).transpose(2, 0, 1)
    else:
        cart_to_body = np.broadcast_to(np.array([[0.0, 1, 0], [0, 0, 1], [1, 0, 0]]), (n, 3, 3))
    return cart_to_body @ mesh_frame_to_cartesian(case, rep)


def body_point_to_mesh(case, rep: str, point) -> np.ndarray:
    """Mesh coordinates, shape ``(dim,)``, of a body point ``(x1, x2, x3)``."""
    x1, x2, x3 = (float(c) for c in point)
    if rep == AXISYMMETRIC:
        return np.array([x1, x2])
    if case.body == RING:
        xy = [x1 * np.cos(x3), x1 * np.sin(x3)]
        return np.array(xy + [x2] if rep == SOLID else xy)
    return np.array([x3, x1, x2] if rep == SOLID else [x3, x2])


def x3_of(case, rep: str, x: np.ndarray) -> np.ndarray:
    """Body coordinate x3 of mesh points ``x`` (ring: theta in ``[0, 2 pi)``; prism: span)."""
    xc = to_cartesian(case, rep, x)
    if case.body == RING:
        return np.mod(np.arctan2(xc[1], xc[0]), 2 * np.pi)
    return xc[0]


def body_coordinates(case, rep: str, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Body coordinates ``(x1, x2, x3)`` of mesh points ``x``; the direction a 2D model leaves
    out is NaN (an axisymmetric section's theta, a plane-strain ring's z, a prism's x1)."""
    xc = to_cartesian(case, rep, x)
    nan = np.full(xc.shape[1], np.nan)
    if case.body == RING:
        x3 = np.mod(np.arctan2(xc[1], xc[0]), 2 * np.pi)
        return np.hypot(xc[0], xc[1]), (nan if rep == PLANE_STRAIN else xc[2]), (nan if rep == AXISYMMETRIC else x3)
    return (nan if rep == PLANE_STRAIN else xc[1]), xc[2], xc[0]


def section_of(case, rep: str, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Section parameters ``(s, t)`` of mesh points ``x``; a dropped direction gives NaN."""
    xc = to_cartesian(case, rep, x)
    if case.body == RING:
        x1, x2 = np.hypot(xc[0], xc[1]), xc[2]
        if rep == PLANE_STRAIN:
            x2 = np.full_like(x1, np.nan)
    else:
        x1, x2 = xc[1], xc[2]
        if rep == PLANE_STRAIN:
            x1 = np.full_like(x2, np.nan)
    return case.section.from_x(x1, x2)


def in_intervals(x3, intervals, period: float | None) -> np.ndarray:
    """Mask of ``x3`` inside any closed interval (modulo ``period`` when given)."""
    x3 = np.asarray(x3, float)
    mask = np.zeros(x3.shape, bool)
    for a, b in intervals:
        if period is None:
            mask |= (x3 >= a) & (x3 <= b)
        else:
            mask |= np.mod(x3 - a, period) <= (b - a)
    return mask
