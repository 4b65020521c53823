"""Material varying along x3: the cut-outs' profile and the harmonic coupling integrals.

Each element of the section carries a factor ``f(x3)`` on its stiffness and density: the case's
``contrast`` inside a cut-out, 1 elsewhere. An element belongs to a cut-out when its centre lies
in the cut-out's parametric box, so cut-out edges should fall on element edges (the paper's
meshes do). Integrals along x3 use a quadrature on each piece between the cut-outs' edges,
where ``f`` is smooth (constant), which makes them exact to round-off for the trigonometric
products of the harmonics kept: Gauss-Legendre transplanted through a conformal map
(:func:`transplanted`, about 1.45 times fewer points at large frequencies), plain
Gauss-Legendre where that takes no more points (:func:`x3_rule`).
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
    """Gauss-Legendre points and weights on [-1, 1], kept (every model of a run asks again).

    numpy's nodes are right to round-off but its weights are not (relative errors of 1e-13 in
    the middle at 1000 points, which integrate ``cos`` to 2e-13 only): one Newton step on
    numpy's nodes by the three-term recurrence, and the weights ``2 / ((1 - x^2) P_n'(x)^2)``
    from it, are right to round-off (1e-16 each, 1e-14 summed at 2000 points). Symmetric.
    """
    x = np.polynomial.legendre.leggauss(n)[0][n // 2:]  # the nonnegative half (and 0 if n is odd)
    for polish in (True, False):
        p_prev, p = np.ones_like(x), x.copy()
        for k in range(2, n + 1):
            p_prev, p = p, ((2 * k - 1) * x * p - (k - 1) * p_prev) / k
        derivative = n * (x * p - p_prev) / (x * x - 1)
        if polish:
            x = x - p / derivative
    if n % 2:
        x[0] = 0.0
    w = 2 / ((1 - x * x) * derivative * derivative)
    x, w = np.concatenate([-x[::-1][:n // 2], x]), np.concatenate([w[::-1][:n // 2], w])
    x.flags.writeable = w.flags.writeable = False
    return x, w


#: the transplanted rule's map ``g(s) = arcsin(alpha s) / arcsin(alpha)``, ``alpha =
#: sech(MAP_DECAY / n)`` for ``n`` points: its singularities at ``s = +-1/alpha`` lie on the
#: Bernstein ellipse where the n-point Gauss rule's error decays as ``exp(-2 MAP_DECAY)``
#: (Kosloff and Tal-Ezer's choice of alpha). Larger values move the points nearer a uniform grid
#: but need more of them for the map's singularities: 36 is within 2 % of the least count over
#: 24-42 from omega 50 to 2000 (benchmarks/README.md)
MAP_DECAY = 36.0


@functools.lru_cache(maxsize=64)
def transplanted(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The n Gauss-Legendre points and weights transplanted through the Kosloff-Tal-Ezer map
    (Hale and Trefethen 2008, SIAM J. Numer. Anal. 46): ``x = g(s)``, ``w g'(s)``. The map spreads
    Gauss-Legendre's points, which crowd the ends of [-1, 1], towards a uniform grid, so a
    band-limited integrand needs up to pi/2 times fewer points."""
    s, w = leggauss(n)
    t = MAP_DECAY / n
    alpha, one_minus_alpha = 1 / math.cosh(t), 2 * math.sinh(t / 2) ** 2 / math.cosh(t)
    # near the ends arcsin amplifies the rounding of alpha s (by 1 / tanh(t): 18 at 1000
    # points): there 1 - alpha s from 1 - s (exact) and 1 - alpha, and
    # arcsin(y) = pi/2 - 2 arcsin(sqrt((1 - y) / 2))
    u = np.abs(s)
    gap = one_minus_alpha + alpha * (1 - u)  # 1 - alpha |s|
    edge = 2 * math.asin(math.sqrt(one_minus_alpha / 2))  # arccos(alpha)
    scale = math.pi / 2 - edge  # arcsin(alpha)
    near_end = 1 - (2 * np.arcsin(np.sqrt(gap / 2)) - edge) / scale
    x = np.where(u < 0.5, np.arcsin(alpha * u) / scale, near_end)
    x = np.copysign(x, s)
    w = w * alpha / (np.sqrt(gap * (1 + alpha * u)) * scale)
    x.flags.writeable = w.flags.writeable = False
    return x, w


def transplanted_points_needed(omega: float) -> int:
    """Points of :func:`transplanted` that integrate ``cos(omega x)`` over [-1, 1] to 1e-14 for
    every frequency up to ``omega``: the least count measured (rule in long double, frequencies
    every 0.25 over the top 30 %) is 7, 12, 16, 23, 36, 55, 91, 163, 303, 443, 720 at omega = 1, 5,
    10, 20, 50, 100, 200, 400, 800, 1200, 2000 (Gauss-Legendre, measured alike: 7, 13, 17, 25, 45,
    74, 130, 238, 447, 654, 1063; omega / pi is the band limit's; ``benchmarks/x3_rule.py``), this
    fit 1 to 6 above them. In double
    precision the nodes' rounding, which the map amplifies near the ends, leaves 1-3e-14 from
    omega 500 to 2000 (numpy's Gauss-Legendre weights left 2-6e-14 there)."""
    return int(math.ceil(0.338 * omega + 3.2 * omega ** (1 / 3) + 7)) + 1


def x3_rule(omega: float, oversampling: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Points and weights on [-1, 1] that integrate ``cos(omega' x)``, ``sin(omega' x)`` to 1e-14
    for every ``omega' <= omega``: the transplanted rule, or Gauss-Legendre's where it needs no
    more points (small ``omega``); ``oversampling`` times as many points (rounded up)."""
    mapped, plain = transplanted_points_needed(omega), gauss_points_needed(omega)
    if mapped < plain:
        return transplanted(int(math.ceil(oversampling * mapped)))
    return leggauss(int(math.ceil(oversampling * plain)))


def gauss_pieces(edges: np.ndarray, top_k: float, oversampling: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Points and weights of :func:`x3_rule` on the pieces between consecutive ``edges``, each
    exact for functions of x3 up to the wavenumber ``top_k``; ``oversampling`` times as many
    points (rounded up)."""
    points, weights = [], []
    for a, b in zip(edges[:-1], edges[1:]):
        x, w = x3_rule(top_k * (b - a) / 2, oversampling)
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
    """Points and weights over the whole x3 range: :func:`x3_rule` on each piece between cut-out
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
