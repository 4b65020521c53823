"""Fourier modes along x3: which basis functions each displacement component carries.

A mode is one harmonic ``l`` of one family:

* ring, family ``'c'`` (the paper's symmetric family): ``u_r, u_z ~ cos(l theta)``,
  ``u_theta ~ sin(l theta)``; for l = 0 this is axial/radial motion (``u_theta`` absent);
* ring, family ``'s'``: ``u_r, u_z ~ sin(l theta)``, ``u_theta ~ -cos(l theta)``; for l = 0
  this is pure torsion (``u_r, u_z`` absent);
* prism, family ``'p'``: ``u1, u2 ~ sin(k x3)``, ``u3 ~ cos(k x3)``, ``k = l pi / length``
  (hinged ends), l >= 1.

Strain rows ``[e11, e22, e33, g12, g13, g23]`` of a mode vary along x3 like the in-plane
components (``psi1``) for rows 0-3 and like the out-of-plane one (``psi3``) for rows 4-5, with
one strain operator per ``l`` shared by both ring families (docs/method.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cases.geometry import PRISM, RING, interval_fourier

#: strain row -> basis type (0: psi1, 1: psi3)
ROW_TYPE = np.array([0, 0, 0, 0, 1, 1])


@dataclass(frozen=True)
class Mode:
    l: int
    family: str  # 'c' | 's' (ring) or 'p' (prism)

    def __str__(self) -> str:
        return f"{self.l}{self.family}" if self.family != "p" else str(self.l)


def modes(body: str, harmonics: int, families=("c",)) -> list[Mode]:
    """All modes a run may use: ring l = 0..harmonics-1 per family; prism l = 1..harmonics."""
    if body == PRISM:
        return [Mode(l, "p") for l in range(1, harmonics + 1)]
    return [Mode(l, f) for f in families for l in range(harmonics)]


def wavenumber(mode: Mode, body: str, length: float) -> float:
    """The factor that multiplies the mode index in the strains: l (ring) or l pi / length."""
    return float(mode.l) if body == RING else mode.l * math.pi / length


def psi(mode: Mode, x3, body: str, length: float):
    """Basis values ``(psi1, psi3)`` at ``x3`` (arrays broadcast)."""
    x3 = np.asarray(x3, float)
    arg = wavenumber(mode, body, length) * x3
    if mode.family == "c":
        return np.cos(arg), np.sin(arg)
    if mode.family == "s":
        return np.sin(arg), -np.cos(arg)
    return np.sin(arg), np.cos(arg)


def psi_squared_integrals(mode: Mode, body: str, length: float) -> tuple[float, float]:
    """Exact ``(int psi1^2, int psi3^2)`` over the x3 range of a homogeneous body."""
    if body == PRISM:
        return length / 2, length / 2
    if mode.l > 0:
        return math.pi, math.pi
    return (2 * math.pi, 0.0) if mode.family == "c" else (0.0, 2 * math.pi)


def psi_integrals(mode: Mode, body: str, length: float) -> tuple[float, float]:
    """Exact ``(int psi1, int psi3)`` over the whole x3 range (the same bases as :func:`psi`)."""
    whole = ((0.0, 2 * math.pi if body == RING else length),)
    kinds = {"c": ("cos", "sin", 1.0), "s": ("sin", "cos", -1.0), "p": ("sin", "cos", 1.0)}[mode.family]
    return (interval_fourier(whole, mode.l, kinds[0], body, length),
            kinds[2] * interval_fourier(whole, mode.l, kinds[1], body, length))


def absent_components(mode: Mode) -> tuple[int, ...]:
    """Components (0-based) whose basis function vanishes identically (ring l = 0)."""
    if mode.l == 0 and mode.family == "c":
        return (2,)
    if mode.l == 0 and mode.family == "s":
        return (0, 1)
    return ()
