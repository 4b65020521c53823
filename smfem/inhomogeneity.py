"""Material varying along x3: the cut-outs' profile and the harmonic coupling integrals.

Each element of the section carries a factor ``f(x3)`` on its stiffness and density: the case's
``contrast`` inside a cut-out, 1 elsewhere. An element belongs to a cut-out when its centre lies
in the cut-out's parametric box, so cut-out edges should fall on element edges (the paper's
meshes do). Integrals along x3 use Gauss-Legendre quadrature on the pieces between the
cut-outs' edges, where ``f`` is smooth (constant), which makes them exact to round-off for
the trigonometric products of the harmonics kept.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from cases.geometry import RING

from . import fourier


def gauss_points_needed(omega: float) -> int:
    """Gauss-Legendre points that integrate ``cos(omega x)`` over [-1, 1] to 1e-14 for every
    frequency up to ``omega`` (measured: 7, 11, 17, 32, 75, 186 points at omega = 1, 4, 10, 30,
    100, 300; Bessel-function decay beyond the degree ``omega``)."""
    return max(8, int(math.ceil(omega / 2 + 5.5 * omega ** (1 / 3))) + 1)


@functools.lru_cache(maxsize=64)
def leggauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre points and weights on [-1, 1], kept: numpy's Newton polish of hundreds of
    points costs milliseconds, and every model of a run (its companions too) asks again."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.flags.writeable = w.flags.writeable = False
    return x, w


def gauss_pieces(edges: np.ndarray, top_k: float, oversampling: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Points and weights of Gauss-Legendre rules on the pieces between consecutive ``edges``,
    each exact for functions of x3 up to the wavenumber ``top_k``; ``oversampling`` times as many
    points (rounded up)."""
    points, weights = [], []
    for a, b in zip(edges[:-1], edges[1:]):
        n = int(math.ceil(oversampling * gauss_points_needed(top_k * (b - a) / 2)))
        x, w = leggauss(n)
        points.append(0.5 * (b - a) * x + 0.5 * (a + b))
        weights.append(0.5 * (b - a) * w)
    return np.concatenate(points), np.concatenate(weights)


def cut_edges(case, lo: float, hi: float) -> np.ndarray:
    """``lo``, ``hi`` and every cut-out edge between them (sorted)."""
    period = 2 * math.pi if case.body == RING else case.length
    cuts = {lo, hi}
    for c in case.cutouts:
        for a, b in c.x3_intervals:
            cuts.update({a % period, b % period} if case.body == RING else {a, b})
    return np.array(sorted(x for x in cuts if lo <= x <= hi))


def varies(case) -> bool:
    """Whether the material varies along x3 (a cut-out of ``contrast`` below 1, or a smooth
    variation): then its harmonics couple; else they are independent."""
    return (bool(case.cutouts) and case.contrast < 1.0) or bool(case.variation)


def x3_quadrature(case, harmonics: int) -> tuple[np.ndarray, np.ndarray]:
    """Points and weights over the whole x3 range: Gauss-Legendre on each piece between cut-out
    edges, exact for the product of two harmonics < ``harmonics``."""
    period = 2 * math.pi if case.body == RING else case.length
    top = 2 * harmonics + max((m for _, m in case.variation), default=0)  # f psi_a psi_b
    return gauss_pieces(cut_edges(case, 0.0, period), top * (1.0 if case.body == RING else math.pi / period))


def element_factor(case, mesh, x3: np.ndarray) -> np.ndarray:
    """(n_elements, n_points) material factor at the x3 points: ``contrast`` in cut-outs, else 1,
    times the case's smooth variation along x3."""
    st = mesh.element_st_centres()
    f = np.ones((mesh.n_elements, len(x3))) * case.variation_factor(x3)[None, :]
    period = 2 * math.pi if case.body == RING else case.length
    for c in case.cutouts:
        inside = (st[:, 0] > c.s_range[0]) & (st[:, 0] < c.s_range[1]) & (st[:, 1] > c.t_range[0]) & (st[:, 1] < c.t_range[1])
        along = np.zeros(len(x3), bool)
        for a, b in c.x3_intervals:
            along |= ((x3 - a) % period < (b - a)) if case.body == RING else ((x3 > a) & (x3 < b))
        f[np.ix_(inside, along)] *= case.contrast
    return f


def coupling_integrals(modes, case, factor: np.ndarray, x3: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``int f psi_a^(l) psi_b^(m) dx3`` per factor profile: shape (n_modes, n_modes, n_rows, 2, 2).

    ``factor`` (n_rows, n_x3) holds the distinct profiles ``f(x3)`` (most elements share one);
    ``a, b`` are the basis types of the strain rows (0: psi1, 1: psi3), see :mod:`smfem.fourier`.
    One matrix product per profile and type pair.
    """
    psi = np.array([fourier.psi(m, x3, case.body, case.length) for m in modes])  # (n_modes, 2, nq)
    out = np.empty((len(modes), len(modes), len(factor), 2, 2))
    for r, f in enumerate(factor):
        for a in range(2):
            weighted = psi[:, a] * (f * w)
            for b in range(2):
                out[:, :, r, a, b] = weighted @ psi[:, b].T
    return out
