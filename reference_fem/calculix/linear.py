"""The reference's quadratic mesh as linear elements on the same nodes, for ccx's explicit
dynamics (which wants linear elements and a lumped mass): each quad9 split 2 x 2 into 4-node
quadrilaterals (CPE4 / CAX4), each hexahedron27 split 2 x 2 x 2 into 8-node hexahedra (C3D8).

Every node of the quadratic mesh is a corner of the split one, so the probes' nodes, the
supports and the initial velocity carry over unchanged. A sub-element keeps its parent's
orientation and its face numbering: its face ``k`` lies on its parent's face ``k`` or inside
the parent.
"""

from __future__ import annotations

import numpy as np

from .serendipity import HEX_EDGES, HEX_FACES

#: the corners of the parent in a lattice of 3 points per direction (0, 1, 2), VTK's order
CORNERS = {
    2: np.array([[0, 0], [2, 0], [2, 2], [0, 2]]),
    3: np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0], [0, 0, 2], [2, 0, 2], [2, 2, 2], [0, 2, 2]]),
}
#: the quad9's mid-sides (edges 0-1, 1-2, 2-3, 3-0) by their corners
QUAD_EDGES = ((0, 1), (1, 2), (2, 3), (3, 0))


def lattice(dim: int) -> np.ndarray:
    """Each local node of a quad9 / hexahedron27 (VTK order) at its lattice point, ``(9 | 27, dim)``:
    a mid-side, face or centre node is the mean of the corners it lies between."""
    corners = CORNERS[dim]
    if dim == 2:
        groups = [(k,) for k in range(4)] + list(QUAD_EDGES) + [tuple(range(4))]
    else:
        groups = [(k,) for k in range(8)] + list(HEX_EDGES) + list(HEX_FACES) + [tuple(range(8))]
    return np.array([corners[list(g)].mean(axis=0) for g in groups]).astype(int)


def _local(dim: int) -> np.ndarray:
    """The split's elements in the parent's local nodes, ``(2 ** dim, 2 ** dim)``: sub-element
    ``s`` (its lattice offset in binary) has the parent's corners shifted to that offset."""
    where = {tuple(p): k for k, p in enumerate(lattice(dim))}
    offsets = np.array(np.meshgrid(*[(0, 1)] * dim, indexing="ij")).reshape(dim, -1).T
    return np.array([[where[tuple(o + c // 2)] for c in CORNERS[dim]] for o in offsets])


def split(cells: np.ndarray) -> np.ndarray:
    """The linear elements of quadratic ``cells`` ``(n, 9 | 27)``: ``(n * 2 ** dim, 4 | 8)``, the
    sub-elements of parent ``e`` at rows ``e * 2 ** dim ...``."""
    dim = 2 if cells.shape[1] == 9 else 3
    return cells[:, _local(dim)].reshape(-1, 2**dim)


def face_children(dim: int, face: int, faces: tuple) -> np.ndarray:
    """The sub-elements (0 ... 2 ** dim - 1) whose face ``face`` (0-based in ``faces``, the
    element's faces by corner) lies on the parent's face ``face``."""
    corners = CORNERS[dim][list(faces[face])]
    axis = int(np.flatnonzero((corners == corners[0]).all(axis=0))[0])  # the face's fixed direction
    level = corners[0, axis]
    points = lattice(dim)
    return np.array([s for s, nodes in enumerate(_local(dim))
                     if (points[nodes[list(faces[face])], axis] == level).all()])
