"""The reference's Lagrange elements (quad9, hexahedron27, VTK order) against CalculiX's
serendipity ones (CPE8/CAX8, C3D20): the serendipity shape functions' values at the Lagrange
face and centre nodes, which fill those nodes in (:func:`.solver.complete`) and, transposed,
share their forces out (:func:`.loads.serendipity_forces`)."""

from __future__ import annotations

import numpy as np

#: a hexahedron's edges and faces by its corners, VTK order (mid-side node 8 + edge, face node 20 + face)
HEX_EDGES = ((0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7))
HEX_FACES = ((0, 3, 7, 4), (1, 2, 6, 5), (0, 1, 5, 4), (3, 2, 6, 7), (0, 1, 2, 3), (4, 5, 6, 7))


def shares(cells: np.ndarray, dim: int) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """``(extra, nodes, weight)`` triples: each Lagrange face or centre node ``extra[i]`` is the
    sum over the triples of ``weight`` times the serendipity nodes ``nodes[i]`` (-1/4 of the
    corners plus 1/2 of the mid-sides on a face or a quad's centre; -1/4 of the corners plus 1/4
    of the mid-sides at a hexahedron's centre). A face node appears once per element it bounds."""
    if dim == 2:
        return [(cells[:, 8], cells[:, :4], -0.25), (cells[:, 8], cells[:, 4:8], 0.5)]
    edge_of = {frozenset(e): 8 + k for k, e in enumerate(HEX_EDGES)}
    mids = [[edge_of[frozenset((face[i], face[(i + 1) % 4]))] for i in range(4)] for face in HEX_FACES]
    faces = np.concatenate([cells[:, 20 + f] for f in range(6)])
    return [(faces, np.concatenate([cells[:, list(face)] for face in HEX_FACES]), -0.25),
            (faces, np.concatenate([cells[:, m] for m in mids]), 0.5),
            (cells[:, 26], cells[:, :8], -0.25), (cells[:, 26], cells[:, 8:20], 0.25)]


def once(extra: np.ndarray, nodes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each extra node with its serendipity nodes once (a face node shared by two elements
    has the same ones in both)."""
    extra, first = np.unique(extra, return_index=True)
    return extra, nodes[first]
