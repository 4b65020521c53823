"""ccx's explicit increment, predicted from the deck, for spacing its output.

ccx 2.20's ``*DYNAMIC, EXPLICIT`` writes its results at every increment whatever ``TIME
POINTS`` say (the thick cylinder at refine 3: 2344 result blocks in its first 3.8 ms against
the 100 grid times; the notched cylinder's whole-body PEEQ: a 2.7 GB .frd by mid-run). Its
``FREQUENCY`` (every N increments) is the one lever, and N follows from the increment ccx will
take. ``calcstabletimeincvol.f`` takes 0.8 x 0.98 x the least over the elements of their
volume over their largest face area times an element factor, divided by the dilatational wave
speed (``ALPHA`` 0). A 2D element is expanded into a brick of unit width, so that length is its
area over its longest edge. The factor is 1 for full integration; for the reduced C3D8R the
sources after 2.20 have 0.625 (then 1/sqrt(3)), but 2.20's increments are half the full
element's: 0.5 (the notched strip's CPE4R at refine 1: 1.59e-7 s printed, 3.26e-7 s predicted
with factor 1). Predicted 4.95e-6 s on the thick cylinder's CPE4 at refine 1, where ccx printed
4.85e-6: 2 % high, so N increments span a little less than predicted (the safe side for the
spacing). A test holds the prediction to ccx's on plane and solid, full and reduced elements.
"""

from __future__ import annotations

import numpy as np

#: ccx's factors on the least element length over the wave speed (calcstabletimeincvol.f)
SAFETY = 0.8 * 0.98
#: the element factor of ccx 2.20: full integration 1, reduced (``...R``) 0.5 (measured, above)
REDUCED_FACTOR = 0.5
#: outputs per dt at least: the probes are read between them by linear interpolation, whose error
#: on a history resolved at dt is (omega dt / 4)^2 / 8, about a tenth of Newmark's at dt
OUTPUTS_PER_DT = 4
#: the faces of a linear hexahedron (VTK's order)
HEX_FACES = ((0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7))


def wave_speed(mat) -> float:
    """The dilatational (P-) wave speed of an elastic material, m/s."""
    return float(np.sqrt(mat.E * (1 - mat.nu) / (mat.rho * (1 + mat.nu) * (1 - 2 * mat.nu))))


def element_lengths(points: np.ndarray, elements: np.ndarray) -> np.ndarray:
    """ccx's length of each linear element: area over longest edge (4-node quadrilaterals, ``points``
    ``(2, n)``), volume over largest face area (8-node hexahedra, ``(3, n)``)."""
    x = points.T[elements]  # (n_elements, corners, dim)
    if x.shape[2] == 2:
        d1, d2 = x[:, 2] - x[:, 0], x[:, 3] - x[:, 1]
        area = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
        edges = np.linalg.norm(x - np.roll(x, -1, axis=1), axis=2)
        return area / edges.max(axis=1)
    faces = [0.5 * np.linalg.norm(np.cross(x[:, f[2]] - x[:, f[0]], x[:, f[3]] - x[:, f[1]]), axis=1)
             for f in HEX_FACES]
    return _hex_volume(x) / np.max(faces, axis=0)


def stable_increment(points: np.ndarray, elements: np.ndarray, speed: np.ndarray, element: str) -> float:
    """The increment ccx's explicit step will take (s), the elements' wave ``speed`` ``(n_elements,)``,
    ``element`` ccx's name of them (a reduced one ends in ``R``)."""
    factor = REDUCED_FACTOR if element.endswith("R") else 1.0
    return float(SAFETY * factor * np.min(element_lengths(points, elements) / speed))


def output_frequency(dt: float, increment: float) -> int:
    """Every how many increments to write, so that at least :data:`OUTPUTS_PER_DT` outputs fall in a dt."""
    return max(1, int(dt / (OUTPUTS_PER_DT * increment)))


def _hex_volume(x: np.ndarray) -> np.ndarray:
    """Volumes of trilinear hexahedra ``(n, 8, 3)`` (VTK order): 2 x 2 x 2 Gauss on ``det J``."""
    g = np.array([-1.0, 1.0]) / np.sqrt(3.0)
    signs = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                      [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float)
    volume = np.zeros(x.shape[0])
    for a in g:
        for b in g:
            for c in g:
                xi = np.array([a, b, c])
                # dN/dxi of each corner at (a, b, c): (8, 3)
                factors = 1 + signs * xi
                dN = np.stack([signs[:, i] * np.prod(np.delete(factors, i, axis=1), axis=1) for i in range(3)], 1) / 8
                J = np.einsum("nkd,ki->ndi", x, dN)
                volume += np.abs(np.linalg.det(J))
    return volume
