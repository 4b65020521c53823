"""The fewest points of the x3 rules that integrate every frequency up to omega to 1e-14.

    python benchmarks/x3_rule.py [--omegas W ...] [--decays C ...] [--tiny]

For each omega, the least n for which the n-point rule integrates ``cos(o x)`` over [-1, 1] to
:data:`TOLERANCE` for every ``o <= omega`` (``o`` every 0.25 over the top 30 %, coarser below):
Gauss-Legendre, and Gauss-Legendre transplanted through the Kosloff-Tal-Ezer map with
``alpha = sech(C / n)`` for each decay ``C`` (:func:`smfem.inhomogeneity.transplanted`, whose
``MAP_DECAY`` is one C). The rules are built and summed in long double (Newton on the Legendre
recurrence from numpy's nodes), so the counts are the rules' own, not double precision's
round-off (which :func:`smfem.inhomogeneity.transplanted_points_needed` states apart). Last
column: the counts :func:`smfem.inhomogeneity.x3_rule` takes, for its formulas' margins.
"""

from __future__ import annotations

import argparse
import functools

import numpy as np

from smfem import inhomogeneity

#: the absolute error on [-1, 1] a count must reach
TOLERANCE = 1e-14
LONG = np.longdouble


@functools.cache
def legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights in long double."""
    x = np.polynomial.legendre.leggauss(n)[0].astype(LONG)
    for _ in range(3):
        p_prev, p = np.ones_like(x), x.copy()
        for k in range(2, n + 1):
            p_prev, p = p, ((2 * k - 1) * x * p - (k - 1) * p_prev) / k
        derivative = n * (x * p - p_prev) / (x * x - 1)
        x = x - p / derivative
    return x, 2 / ((1 - x * x) * derivative * derivative)


def rule(n: int, decay: float) -> tuple[np.ndarray, np.ndarray]:
    """The n-point rule in long double: Gauss-Legendre (``decay`` 0) or transplanted."""
    s, w = legendre(n)
    if decay == 0:
        return s, w
    alpha = 1 / np.cosh(LONG(decay) / n)
    scale = np.arcsin(alpha)
    return np.arcsin(alpha * s) / scale, w * alpha / (np.sqrt(1 - (alpha * s) ** 2) * scale)


def error(x: np.ndarray, w: np.ndarray, omega: float) -> float:
    """Largest error on ``cos(o x)`` over ``o <= omega``."""
    o = np.concatenate([np.linspace(1e-3, 0.7 * omega, int(0.3 * omega) + 30),
                        np.arange(0.7 * omega, omega, 0.25), [omega]]).astype(LONG)
    worst = 0.0
    for part in np.array_split(o, max(1, len(o) // 400)):
        exact = 2 * np.sin(part) / part
        worst = max(worst, float(np.abs(np.cos(part[:, None] * x[None, :]) @ w - exact).max()))
    return worst


def least(omega: float, decay: float) -> int:
    """The fewest points of the rule that reach :data:`TOLERANCE` up to ``omega`` (bisection)."""
    ok = lambda n: error(*rule(n, decay), omega) <= TOLERANCE
    high = max(8, int(omega / np.pi) + 10)
    while not ok(high):
        high = int(high * 1.15) + 1
    low = 3
    while high - low > 1:
        mid = (low + high) // 2
        low, high = (low, mid) if ok(mid) else (mid, high)
    return high


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--omegas", nargs="+", type=float,
                        default=[1, 5, 10, 20, 50, 100, 200, 400, 800, 1200, 2000])
    parser.add_argument("--decays", nargs="+", type=float, default=[inhomogeneity.MAP_DECAY])
    parser.add_argument("--tiny", action="store_true", help="two small omegas")
    args = parser.parse_args(argv)
    omegas = [5.0, 20.0] if args.tiny else args.omegas
    print("| omega | Gauss-Legendre | " + " | ".join(f"transplanted C={c:g}" for c in args.decays)
          + " | x3_rule |")
    print("|---" * (len(args.decays) + 3) + "|")
    for omega in omegas:
        counts = [least(omega, c) for c in (0.0, *args.decays)]
        used = len(inhomogeneity.x3_rule(omega)[0])
        print(f"| {omega:g} | " + " | ".join(str(n) for n in counts) + f" | {used} |", flush=True)


if __name__ == "__main__":
    main()
