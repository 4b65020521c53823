"""Scene geometry shared by every solver: cross-sections, coordinate conventions, loads, probes.

Coordinate conventions (the one place that defines them)
---------------------------------------------------------
Ring body (body of revolution): cross-section coordinates ``x1 = r`` (radius), ``x2 = z``
(axis), and ``x3 = theta`` in radians, counter-clockwise, in ``[0, 2 pi)``. Displacement
components 1, 2, 3 are ``u_r``, ``u_z``, ``u_theta``. Cartesian: ``x = r cos(theta)``,
``y = r sin(theta)``, ``z = z``.

Prismatic body: cross-section coordinates ``x1`` (width) and ``x2`` (height), ``x3`` along the
length in ``[0, length]``; components 1, 2, 3 are ``u1``, ``u2``, ``u3``. Cartesian: ``x = x3``
(span), ``y = x1`` (width), ``z = x2`` (height), so that the strip's span runs along ``x``.

A cross-section is one mapped block with parametric axes ``s`` and ``t``:
``kind = 'rect'`` maps ``(s, t) -> (x1, x2) = (s, t)``;
``kind = 'polar'`` maps ``(s, t) -> (x1, x2) = (s sin t, s cos t)`` (a spherical-shell section
of radius ``s`` at polar angle ``t`` from the axis).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

RING = "ring"
PRISM = "prism"

#: edge names of a section block, in parametric terms
EDGES = ("s_min", "s_max", "t_min", "t_max")


@dataclass(frozen=True)
class Axis:
    """A graded 1-D grid: ``breaks[k] .. breaks[k + 1]`` is split into ``counts[k]`` equal parts."""

    breaks: tuple[float, ...]
    counts: tuple[int, ...]
    #: False for a direction the solution does not vary along (one element across a plane-strain
    #: width or axial length): ``refine`` leaves it alone
    refinable: bool = True

    def __post_init__(self):
        if len(self.breaks) != len(self.counts) + 1:
            raise ValueError("Axis needs one more break than counts")

    def grid(self, scale: float = 1, extra=()) -> np.ndarray:
        """Node coordinates, shape ``(n_elements + 1,)``, each segment split into ``scale`` times
        its count (rounded, at least one element: ``scale`` < 1 coarsens). ``extra`` points (a
        cut-out's edges) inside a segment split it, each part keeping the segment's element
        size (rounded, at least one): where they fall on the grid already, nothing changes;
        a coarsened grid keeps them as nodes."""
        scale = scale if self.refinable else 1
        parts = []
        for a, b, n in zip(self.breaks[:-1], self.breaks[1:], self.counts):
            tol = 1e-9 * (b - a)
            cuts = sorted({a, b} | {float(e) for e in extra if a + tol < e < b - tol})
            if len(cuts) == 2:
                parts.append(np.linspace(a, b, max(1, int(round(n * scale))) + 1)[:-1])
                continue
            h = (b - a) / max(1.0, n * scale)
            parts += [np.linspace(c0, c1, max(1, int(round((c1 - c0) / h))) + 1)[:-1] for c0, c1 in zip(cuts[:-1], cuts[1:])]
        return np.concatenate(parts + [np.array([self.breaks[-1]])])

    @property
    def span(self) -> tuple[float, float]:
        return self.breaks[0], self.breaks[-1]


@dataclass(frozen=True)
class Section:
    """Cross-section as a structured block; ``edges`` names the block's edges for loads and BCs."""

    kind: str
    s: Axis
    t: Axis
    edges: dict[str, str] = field(default_factory=dict)

    def to_x(self, s, t):
        """Map parametric ``(s, t)`` to section coordinates ``(x1, x2)``; arrays broadcast."""
        s, t = np.asarray(s, float), np.asarray(t, float)
        if self.kind == "rect":
            return s, t
        if self.kind == "polar":
            return s * np.sin(t), s * np.cos(t)
        raise ValueError(f"unknown section kind {self.kind!r}")

    def from_x(self, x1, x2):
        """Inverse of :meth:`to_x`: parametric ``(s, t)`` of section point ``(x1, x2)``."""
        x1, x2 = np.asarray(x1, float), np.asarray(x2, float)
        if self.kind == "rect":
            return x1, x2
        if self.kind == "polar":
            return np.hypot(x1, x2), np.arctan2(x1, x2)
        raise ValueError(f"unknown section kind {self.kind!r}")

    def edge(self, name: str) -> str:
        """Parametric edge (one of EDGES) for a named edge or a parametric name."""
        return name if name in EDGES else self.edges[name]

    def inside(self, n: int = 7):
        """The section protocol: ``(x1, x2)`` of n x n points inside the block, off its edges
        and the axis (as quadrature points are), shape (n, n)."""
        (s0, s1), (t0, t1) = self.s.span, self.t.span
        f = (np.arange(n) + 0.5) / n
        return self.to_x(s0 + (s1 - s0) * f[:, None], t0 + (t1 - t0) * f[None, :])

    def contains(self, x1: float, x2: float) -> bool:
        """The section protocol: whether section point ``(x1, x2)`` lies in the block (to round-off)."""
        s, t = (float(v) for v in self.from_x(x1, x2))
        for value, axis in ((s, self.s), (t, self.t)):
            lo, hi = axis.span
            slack = 1e-9 * max(abs(lo), abs(hi), hi - lo)
            if not lo - slack <= value <= hi + slack:
                return False
        return True

    def mesh(self, scale: float = 1, extra=((), ()), order: int = 1):
        """The section protocol (:mod:`cases.section_mesh`): the block's structured mesh."""
        from .section_mesh import block_mesh

        return block_mesh(self, scale, extra, order)


@dataclass(frozen=True)
class Cutout:
    """Region of absent material: parametric box of the section times intervals along x3.

    SMFEM models it as contrast material; the reference FEM meshes it as a hole.
    """

    s_range: tuple[float, float]
    t_range: tuple[float, float]
    x3_intervals: tuple[tuple[float, float], ...]


@dataclass(frozen=True)
class Region:
    """A part of the section made of its own material (the case's ``material`` fills the rest).

    On a mapped block it is the parametric box ``s_range`` x ``t_range`` (its limits are grid
    lines at every resolution); on a mesh section (:mod:`cases.msh_section`) it is the physical
    surface ``name``, and the ranges are None. It runs all along x3.
    """

    name: str
    material: object  # a cases.material.Material (or another law's data)
    s_range: tuple[float, float] | None = None
    t_range: tuple[float, float] | None = None

    def contains(self, s, t) -> np.ndarray:
        """Mask of the parametric points ``(s, t)`` (element centres) inside the box."""
        s, t = np.asarray(s, float), np.asarray(t, float)
        return (s > self.s_range[0]) & (s < self.s_range[1]) & (t > self.t_range[0]) & (t < self.t_range[1])


@dataclass(frozen=True)
class Amplitude:
    """A load's history in time: the factor through the points ``(t, factor)``, linear between
    them and constant before the first and after the last (the CalculiX/Abaqus ``*AMPLITUDE``
    convention). A load without one is a step: on at t = 0 and held."""

    points: tuple[tuple[float, float], ...]

    def __post_init__(self):
        t = [p[0] for p in self.points]
        if len(self.points) < 2 or any(len(p) != 2 for p in self.points):
            raise ValueError("an amplitude needs at least two (t, factor) points")
        if not np.isfinite(np.asarray(self.points, float)).all():
            raise ValueError("an amplitude's times and factors must be finite numbers")
        if any(b <= a for a, b in zip(t, t[1:])):
            raise ValueError("an amplitude's times must increase strictly")

    def __call__(self, t):
        """The factor at ``t`` (a number or an array)."""
        times, factors = zip(*self.points)
        value = np.interp(t, times, factors)
        return float(value) if np.ndim(value) == 0 else value

    @property
    def times(self) -> tuple[float, ...]:
        """Where the factor's slope may change."""
        return tuple(p[0] for p in self.points)


@dataclass(frozen=True)
class Pressure:
    """Pressure (compression positive) normal to the undeformed surface ``edge``.

    Along x3 it is ``q`` on ``x3_intervals`` and zero elsewhere; with ``mode = l`` it is instead
    the single Fourier term ``q psi_l(x3)`` (ring: cos(l x3); prism: sin(l pi x3 / length)).
    ``amplitude`` scales it in time (:class:`Amplitude`; none: a step). With ``speed`` (rad/s on
    a ring, m/s on a prism) the intervals move along x3: at time t each one covers
    ``[a + speed t, b + speed t]``, clipped to ``[0, length]`` on a prism (so a patch may start
    outside the body and enter it) and taken modulo 2 pi on a ring (:meth:`intervals_at`).
    """

    q: float
    edge: str
    x3_intervals: tuple[tuple[float, float], ...] = ()
    mode: int | None = None
    amplitude: Amplitude | None = None
    speed: float = 0.0

    @property
    def moving(self) -> bool:
        return self.speed != 0.0

    @property
    def timed(self) -> bool:
        """Whether the load is anything but a step held in place."""
        return self.moving or self.amplitude is not None

    def intervals_at(self, t: float, body: str, length: float) -> tuple[tuple[float, float], ...]:
        """The x3 intervals the pressure covers at time ``t`` (empty ones left out)."""
        return tuple((float(a), float(b)) for a, b in self.ends_at(t, body, length) if b > a)

    def ends_at(self, t, body: str, length: float) -> tuple:
        """Each interval's ends at times ``t`` (arrays as ``t`` is), a prism's clipped to
        ``[0, length]`` (an interval outside it has equal ends: it integrates to zero), for
        :func:`interval_fourier` at many times. A ring's are shifted only: the basis functions
        are periodic, so a shifted interval needs no wrapping."""
        shift = self.speed * np.asarray(t, float)
        ends = ((a + shift, b + shift) for a, b in self.x3_intervals)
        return tuple(ends if body == RING else ((np.clip(a, 0.0, length), np.clip(b, 0.0, length)) for a, b in ends))

    def times_of_change(self, body: str, length: float, t_end: float) -> tuple[float, ...]:
        """The times in (0, t_end) at which the load's history has a kink: its amplitude's points,
        and on a prism where a moving interval's end meets the body's end."""
        times = set(self.amplitude.times if self.amplitude is not None else ())
        if self.moving and body == PRISM:
            times |= {(x - e) / self.speed for a, b in self.x3_intervals for e in (a, b) for x in (0.0, length)}
        return tuple(sorted(t for t in times if 0.0 < t < t_end))


@dataclass(frozen=True)
class Force:
    """A distributed force ``pattern(x1, x2, x3) * time(t)``: per unit volume (a body force),
    or with ``edge`` per unit area of the surface that section edge sweeps (a traction, any
    direction). ``pattern`` holds the three components (in the body's coordinates,
    :mod:`cases.manufactured` expressions of ``x1, x2, x3``), ``time`` an expression of ``t``.
    A case sums its terms: a manufactured motion ``U(x) T(t)`` needs two body forces, ``rho U``
    times ``T''`` and ``-div sigma(U)`` times ``T``, and on a free edge the traction
    ``sigma(U) n`` times ``T``. ``amplitude`` (:class:`Amplitude`) multiplies ``time``."""

    pattern: tuple[str, str, str]
    time: str = "1"
    edge: str | None = None
    amplitude: Amplitude | None = None


@dataclass(frozen=True)
class Motion:
    """A known exact displacement ``pattern(x1, x2, x3) * time(t)`` (body components,
    :mod:`cases.manufactured` expressions), as a manufactured scene has: a solver given one
    reports the relative L2 error of its displacement over the body at the last step
    (``info['error_l2']``), each with its own shape functions and quadrature."""

    pattern: tuple[str, str, str]
    time: str = "1"


#: two shifts along x3, as fractions of the period, under which only a uniform pattern is unchanged
UNIFORM_SHIFTS = (0.618, 0.1 * math.sqrt(2))


@dataclass(frozen=True)
class Support:
    """Zero displacement of ``components`` (1-based) on ``edge``, or on every node if ``edge='all'``."""

    edge: str
    components: tuple[int, ...]


@dataclass(frozen=True)
class InitialVelocity:
    """Uniform initial velocity ``value`` of displacement component ``component``: of the whole
    section, or of one body (region) when ``region`` names it."""

    component: int
    value: float
    region: str | None = None


@dataclass(frozen=True)
class Wall:
    """Rigid wall facing the section edge ``edge`` across an initial ``gap``, with friction.

    ``slope`` tilts the wall about an axis normal to the plane (x, x2) of the section at
    x3 = 0: the gap at a face point grows as ``gap + slope (x_max - x)``, where ``x`` is the
    point's first Cartesian coordinate (ring: ``r cos x3``) and ``x_max`` its largest value on
    the face, so the wall is first touched at x3 = 0, on the face's outer edge. The wall's
    normal is kept along the face normal (small-slope model: the normal force is right to
    O(slope^2); its tangential component, O(slope) of it, is left out in both solvers).
    """

    edge: str
    gap: float
    friction: float
    slope: float = 0.0

    def gap_at(self, x, x_max: float):
        """Initial gap at face points of first Cartesian coordinate ``x``."""
        return self.gap + self.slope * (x_max - x)


@dataclass(frozen=True)
class ContactPair:
    """Two bodies' faces that meet through the contact layer (paper (17)-(19)): ``face`` of one
    body and ``other`` of another, section edges named ``'body.edge'`` (:mod:`cases.bodies`).

    The initial gap at every point is the geometric distance between the two faces along the
    outward normal of ``face`` (zero where they touch, a clearance where they are apart, negative
    where they overlap); ``interference`` (length) is the overlap the scene states (a shrink
    fit): faces overlapping by more are refused (:func:`cases.bodies.check_pairs`). Coulomb
    ``friction``; no adhesion: the layer carries no normal tension.
    """

    face: str
    other: str
    friction: float = 0.0
    interference: float = 0.0


@dataclass(frozen=True)
class Probe:
    """A recorded quantity.

    kind
        ``'point'``: ``field`` component at section point ``(x1, x2)`` and ``x3``;
        ``'max'``: maximum of ``field`` over the body;
        ``'edge_mean'``: mean of ``field`` component over the face ``edge`` (area-weighted);
        ``'body_mean'``: mean over the volume (mass-weighted), over one body or region when
        ``region`` names it.
    field
        ``'u'`` (displacement, m or in), ``'v'`` (velocity), ``'sigma'`` (stress), ``'peps'``
        (equivalent plastic strain sqrt(2/3 eps_p:eps_p)).
    component
        ``(i,)`` for vectors, ``(i, j)`` for stresses, 1-based, in the body's coordinates;
        ``('n', 'n')`` is the normal stress on ``edge``.
    """

    name: str
    kind: str
    field: str
    component: tuple = ()
    point: tuple[float, float, float] | None = None
    edge: str | None = None
    region: str | None = None


def interval_fourier(intervals, l, family: str, body: str, length: float = 2 * math.pi):
    """Exact integral over ``intervals`` of the basis function of harmonic ``l``.

    Ring: ``cos(l x3)`` (family ``'cos'``) or ``sin(l x3)`` (``'sin'``).
    Prism: ``sin(l pi x3 / length)`` (``'sin'``) or ``cos(...)`` (``'cos'``).
    ``l`` and the intervals' ends may be numpy arrays (broadcast against each other: many
    harmonics, or a moving load's ends at many times, :meth:`Pressure.ends_at`); a float for
    scalars.
    """
    l = np.asarray(l)
    k = (l if body == RING else l * math.pi / length).astype(float)
    zero = k == 0
    safe = np.where(zero, 1.0, k)
    total = 0.0
    for a, b in intervals:
        if family == "cos":
            total = total + np.where(zero, np.subtract(b, a), (np.sin(k * b) - np.sin(k * a)) / safe)
        else:
            total = total + np.where(zero, 0.0, (np.cos(k * a) - np.cos(k * b)) / safe)
    return float(total) if np.ndim(total) == 0 else total
