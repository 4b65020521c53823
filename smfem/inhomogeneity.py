"""Material varying along x3: the cut-outs' profile and the harmonic coupling integrals.

Each element of the section carries a factor ``f(x3)`` on its stiffness and density: the case's
``contrast`` inside a cut-out, 1 elsewhere. An element belongs to a cut-out when its centre lies
in the cut-out's parametric box, so cut-out edges should fall on element edges (the paper's
meshes do). Integrals along x3 use Gauss-Legendre quadrature on the pieces between the
cut-outs' edges, where ``f`` is smooth (constant), which makes them exact to round-off for
the trigonometric products of the harmonics kept.
"""

from __future__ import annotations

import math

import numpy as np

from cases.geometry import RING

from . import fourier


def x3_quadrature(case, harmonics: int, min_points: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Points and weights along x3: Gauss-Legendre on each piece between cut-out edges.

    Each piece gets enough points to integrate a product of two harmonics < ``harmonics``
    (with the density of a factor 1.5 over the Nyquist count) exactly.
    """
    period = 2 * math.pi if case.body == RING else case.length
    cuts = {0.0, period}
    for c in case.cutouts:
        for a, b in c.x3_intervals:
            cuts.update({a % period, b % period} if case.body == RING else {a, b})
    edges = np.array(sorted(x for x in cuts if 0.0 <= x <= period))
    top_k = 2 * harmonics * (1.0 if case.body == RING else math.pi / case.length)
    points, weights = [], []
    for a, b in zip(edges[:-1], edges[1:]):
        n = max(min_points, int(math.ceil(1.5 * top_k * (b - a) / 2)) + 4)
        x, w = np.polynomial.legendre.leggauss(n)
        points.append(0.5 * (b - a) * x + 0.5 * (a + b))
        weights.append(0.5 * (b - a) * w)
    return np.concatenate(points), np.concatenate(weights)


def element_factor(case, mesh, x3: np.ndarray) -> np.ndarray:
    """(n_elements, n_points) material factor at the x3 points: ``contrast`` in cut-outs, else 1."""
    st = mesh.element_st_centres()
    f = np.ones((mesh.n_elements, len(x3)))
    period = 2 * math.pi if case.body == RING else case.length
    for c in case.cutouts:
        inside = (st[:, 0] > c.s_range[0]) & (st[:, 0] < c.s_range[1]) & (st[:, 1] > c.t_range[0]) & (st[:, 1] < c.t_range[1])
        along = np.zeros(len(x3), bool)
        for a, b in c.x3_intervals:
            along |= ((x3 - a) % period < (b - a)) if case.body == RING else ((x3 > a) & (x3 < b))
        f[np.ix_(inside, along)] = case.contrast
    return f


def coupling_integrals(modes, case, factor: np.ndarray, x3: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``int f psi_a^(l) psi_b^(m) dx3`` per element: shape (n_modes, n_modes, n_elements, 2, 2).

    ``a, b`` are the basis types of the strain rows (0: psi1, 1: psi3), see :mod:`smfem.fourier`.
    """
    psi = np.array([fourier.psi(m, x3, case.body, case.length) for m in modes])  # (n_modes, 2, nq)
    return np.einsum("eq,laq,mbq,q->lmeab", factor, psi, psi, w, optimize=True)
