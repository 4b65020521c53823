"""Which harmonics a nonlinear run needs: the symmetry of loads and material along x3.

Plasticity couples every pair of harmonics that the symmetry of the problem allows, so the
modes of a nonlinear run follow from that symmetry, not from the load alone:
* ring: reflection about theta = 0 removes the sine family; a rotational period 2 pi / n keeps
  only harmonics that are multiples of n (n = 0: axisymmetric, harmonic 0 only);
* prism: reflection about mid-span keeps the odd harmonics only.
Force terms (body forces, tractions) and a material varying along x3 are tried under the same
maps at sample points (:func:`forces_invariant`).
A tilted wall (``case.wall.slope``) gives a contact gap varying as cos(x3): the cosine family.
A moving load counts by every place along its path: one turning round a ring excites both
families.
"""

from __future__ import annotations

import math

import numpy as np

from cases.geometry import RING, UNIFORM_SHIFTS

from .fourier import Mode


def x3_pattern(case, x3: np.ndarray) -> np.ndarray:
    """A function of x3 that shares every symmetry of the loads, velocities and cut-outs."""
    period = 2 * math.pi if case.body == RING else case.length
    out = np.zeros_like(x3)
    weights = iter(math.sqrt(k + 2) for k in range(1000))  # incommensurate: no accidental cancelling
    for load in case.loads:
        if load.mode is not None:
            k = load.mode if case.body == RING else load.mode * math.pi / case.length
            out += next(weights) * (np.cos(k * x3) if case.body == RING else np.sin(k * x3))
            continue
        # a moving load by its place at several times, each with its own weight: the pattern
        # keeps a symmetry only if every place along the path keeps it
        for t in np.linspace(0.0, case.t_end, 17) if load.moving else (0.0,):
            out += next(weights) * _inside(x3, load.intervals_at(t, case.body, case.length), case.body, period)
    for cut in case.cutouts:
        out += next(weights) * _inside(x3, cut.x3_intervals, case.body, period)
    if case.wall is not None and case.wall.slope:
        out += next(weights) * np.cos(x3)  # the gap of a tilted wall varies as r cos(x3)
    return out


def _inside(x3: np.ndarray, intervals, body: str, period: float) -> np.ndarray:
    """Mask of the points ``x3`` inside ``intervals`` (a ring's modulo 2 pi)."""
    inside = np.zeros_like(x3, bool)
    for a, b in intervals:
        inside |= ((x3 - a) % period < (b - a)) if body == RING else ((x3 > a) & (x3 < b))
    return inside


def forces_invariant(case, x3_image, signs=(1.0, 1.0, 1.0)) -> bool:
    """Whether the case's force terms and material variation are unchanged by the map
    ``x3 -> x3_image(x3)`` with the components' ``signs`` (a reflection turns the x3 component)."""
    if not case.forces and not case.variation:
        return True
    from cases.manufactured import forces_invariant as invariant  # sympy: only for a case that has forces

    period = 2 * math.pi if case.body == RING else case.length
    x3 = (np.arange(97) + 0.5 * math.sqrt(2)) * period / 97
    return np.allclose(case.variation_factor(x3), case.variation_factor(x3_image(x3)), rtol=1e-9, atol=1e-12) \
        and invariant(case.forces, case.section, period, x3_image, signs)


def nonlinear_modes(case, candidates: list[Mode]) -> list[Mode]:
    """The candidate modes that the symmetry of the problem allows."""
    period = 2 * math.pi if case.body == RING else case.length
    x = (np.arange(4096) + 0.5 * math.sqrt(2) - 0.5) * period / 4096  # off every interval edge
    g = x3_pattern(case, x)
    atol = 1e-12 * (1 + np.abs(g).max())

    def same(image) -> bool:
        """The pattern at ``image(x)`` is ``g``: tried on every 16th point first, where nearly
        every turn of the symmetry search already fails (setup time), then on all."""
        return all(np.allclose(g[sub], x3_pattern(case, image(x[sub])), atol=atol)
                   for sub in (slice(None, None, 16), slice(None)))

    if case.body != RING:
        mirror = same(lambda z: period - z) and forces_invariant(case, lambda z: period - z, (1, 1, -1))
        return [m for m in candidates if m.l % 2 == 1] if mirror else candidates
    reflect = same(lambda z: -z) and forces_invariant(case, lambda z: -z, (1, 1, -1))
    families = ("c",) if reflect else ("c", "s")
    turns = lambda k: same(lambda z: z + period / k) and forces_invariant(case, lambda z: z + period / k)
    if np.allclose(g, g.mean(), atol=atol) and all(forces_invariant(case, lambda z, a=a: z + a * period)
                                               for a in UNIFORM_SHIFTS):
        n = 0
    else:
        n = _largest_turn(turns)
    keep = lambda m: (m.l == 0) if n == 0 else (m.l % n == 0)
    return [m for m in candidates if m.family in families and keep(m)]


#: the largest rotational symmetry order tried (2 pi / n)
MAX_TURNS = 256


def _largest_turn(turns) -> int:
    """The largest ``k <= MAX_TURNS`` with ``turns(k)``. The turns that leave a pattern unchanged
    form a cyclic group, so the valid ``k`` are the divisors of one ``n``: the largest power of
    each prime that passes gives ``n`` in about 60 tests rather than 256 (setup time)."""
    n = 1
    for p in (p for p in range(2, MAX_TURNS + 1) if all(p % q for q in range(2, math.isqrt(p) + 1))):
        q = p
        while q <= MAX_TURNS and turns(q):
            n, q = n * p, q * p
    return max(d for d in range(1, MAX_TURNS + 1) if n % d == 0)
