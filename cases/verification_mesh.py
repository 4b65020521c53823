"""The manufactured scene on a mesh section: an L-shaped (non-convex) cross-section meshed with
unstructured quadrilaterals in two physical surfaces, the code verification of the mesh-section
path (:mod:`cases.msh_section`, :func:`cases.section_mesh.unstructured_mesh`).

The L is the unit square of (s, t) less its top-right quarter, on the span of
:data:`cases.verification.SPANS` (ring: r in [1, 2], z in [0, 1]; prism: [0, 1]^2). Its mesh is
made of a few convex polygons (a pentagon, quadrilaterals, triangles), each split into
quadrilaterals round its centroid (:func:`subdivide`), so that corners of valence 3 and 5 occur;
it is written as a gmsh file (:func:`write`) for :func:`cases.msh_section.read_msh` to read, and
refined by splitting every element k x k (``refine = k``). The motion is that of
:mod:`cases.verification` (its harmonics along x3, its time function, its material varying along
x3) with another section factor, one that vanishes on the whole boundary of the L: the product
of the distances to the lines of its six edges times the same gentle exponential. The L is
fixed on all its edges (physical curves ``outer`` and ``notch``).
"""

from __future__ import annotations

import math
from functools import cache

import meshio
import numpy as np
import sympy as sp

from . import manufactured as mf
from . import verification
from .case import Case
from .geometry import PRISM, RING, Motion, Probe, Region, Support
from .material import Material

#: the L's polygons in (s, t): corners of the L, its re-entrant corner (0.5, 0.5), two interior
#: points (the corners of valence 3 in the mesh); each polygon counter-clockwise
POINTS = np.array([(0, 0), (0.5, 0), (1, 0), (1, 0.5), (0.5, 0.5), (0.5, 1), (0, 1), (0, 0.5),
                   (0.3, 0.3), (0.68, 0.2)])
POLYGONS = ((0, 1, 8, 7), (1, 4, 8), (8, 4, 5, 6, 7), (1, 2, 9), (2, 3, 4, 9), (1, 9, 4))
#: the physical surfaces: polygons by name (their interface, the path (0.5, 0) - (0.3, 0.3) -
#: (0.5, 0.5), crosses the motion's nodal lines only at its ends)
SURFACES = {"leg": (0, 2), "foot": (1, 3, 4, 5)}
#: the probe point in (s, t), and x3 as in :data:`cases.verification.POINTS`
PROBE_ST = (0.25, 0.25)


def subdivide(points, polygons) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each convex n-gon split into n quadrilaterals (its centroid, the mid-points of two
    neighbouring sides and the corner between them): a conforming mesh whose centroids have
    valence n.

    Parameters
    ----------
    points : (n_points, 2) float
    polygons : sequence of index sequences, counter-clockwise

    Returns
    -------
    x : (n_nodes, 2) float
    quads : (n_quads, 4) int, counter-clockwise
    polygon : (n_quads,) int, the polygon each quadrilateral is of
    """
    points = np.asarray(points, float)
    x, ids, quads, polygon = [], {}, [], []

    def node(p):
        key = tuple(np.round(p, 12))
        if key not in ids:
            ids[key] = len(x)
            x.append(p)
        return ids[key]

    for k, poly in enumerate(polygons):
        corner = points[list(poly)]
        mids = (corner + np.roll(corner, -1, axis=0)) / 2  # mids[i]: side i -> i + 1
        centre = node(corner.mean(axis=0))
        for i in range(len(poly)):
            quads.append([centre, node(mids[i - 1]), node(corner[i]), node(mids[i])])
            polygon.append(k)
    return np.array(x), np.array(quads), np.array(polygon)


def boundary_lines(quads) -> np.ndarray:
    """The element sides on one element only, counter-clockwise round it: ``(n, 2)``."""
    sides = quads[:, [0, 1, 1, 2, 2, 3, 3, 0]].reshape(-1, 2)
    _, group, count = np.unique(np.sort(sides, axis=1), axis=0, return_inverse=True,
                                return_counts=True)
    return sides[count[group.ravel()] == 1]


def to_x(body: str, st) -> np.ndarray:
    """Section coordinates ``(n, 2)`` of (s, t) points of the unit square on ``body``'s span."""
    (s0, s1), (t0, t1) = verification.SPANS[body]
    st = np.asarray(st, float)
    return np.column_stack([s0 + (s1 - s0) * st[:, 0], t0 + (t1 - t0) * st[:, 1]])


def write(path, body: str):
    """Write the L's quad4 mesh on ``body``'s span to the gmsh file ``path`` (MSH 2.2): physical
    curves ``outer`` and ``notch`` (the two edges at the re-entrant corner), surfaces ``leg``
    and ``foot``. Returns ``path``."""
    st, quads, polygon = subdivide(POINTS, POLYGONS)
    lines = boundary_lines(quads)
    middle = st[lines].mean(axis=1)
    notch = np.all(middle >= 0.5 - 1e-12, axis=1)
    blocks = [("line", lines[~notch], 1), ("line", lines[notch], 2)]
    blocks += [("quad", quads[np.isin(polygon, group)], 3 + k)
               for k, group in enumerate(SURFACES.values())]
    names = {"outer": [1, 1], "notch": [2, 1]} | {n: [3 + k, 2] for k, n in enumerate(SURFACES)}
    tags = [np.full(len(cells), tag) for _, cells, tag in blocks]
    mesh = meshio.Mesh(np.column_stack([to_x(body, st), np.zeros(len(st))]),
                       [(kind, cells) for kind, cells, _ in blocks],
                       cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
                       field_data={name: np.array(v) for name, v in names.items()})
    meshio.write(path, mesh, file_format="gmsh22", binary=False)
    return path


def motion(body: str) -> list[sp.Expr]:
    """``U(x1, x2, x3)``: :func:`cases.verification.motion`'s harmonics along x3 times
    ``64 s (1 - s) t (1 - t) (1 - 2 s) (1 - 2 t) exp((s + t) / 2)``, zero on every edge of the
    L (and on the inner continuations of its notch's edges: a polynomial that vanishes on an
    edge vanishes on its whole line)."""
    (s0, s1), (t0, t1) = verification.SPANS[body]
    s, t = (mf.X1 - s0) / (s1 - s0), (mf.X2 - t0) / (t1 - t0)
    factor = 64 * s * (1 - s) * t * (1 - t) * (1 - 2 * s) * (1 - 2 * t) * sp.exp((s + t) / 2)
    # the square's motion is its section bubble times a factor of x3 alone: keep the latter
    return [factor * c.as_independent(mf.X3, as_Add=False)[1] for c in verification.motion(body)]


@cache
def forces(body: str, time: str, a: float) -> tuple:
    """The body-force terms that make :func:`motion` times the time function ``time`` exact in
    the material varying as ``1 + a cos(2 k x3)``, one displacement component at a time (the
    whole motion's elastic force is longer than an expression may be,
    :data:`cases.expressions.MAX_LENGTH`); derived once per body, time and ``a``."""
    k = 1 if body == RING else sp.pi / verification.LENGTH
    factor = 1 + a * sp.cos(verification.VARIATION_MODE * k * mf.X3)
    U, g = motion(body), verification.time_function(time)
    one_by_one = ([c if j == i else 0 for j, c in enumerate(U)] for i in range(3))
    return tuple(term for Ui in one_by_one
                 for term in mf.motion_body_forces(Ui, g, body, factor, verification.NU, factor))


def build(body: str, section, params: dict | None = None) -> Case:
    """The manufactured scene of ``body`` on ``section`` (the L read from :func:`write`'s file)
    at ``params`` (over :data:`cases.verification.DEFAULTS`; ``element`` as any scene's)."""
    p = {**verification.DEFAULTS, **(params or {})}
    material = Material(1.0, verification.NU, 1.0)
    # the body force is one field over the whole L: both regions must have the same constants
    # (what the two surfaces check is the path from physical surfaces to per-element materials)
    regions = tuple(Region(name, material) for name in SURFACES)
    x1, x2 = to_x(body, [PROBE_ST])[0]
    point = (float(x1), float(x2), verification.POINTS[body][2])
    time = str(verification.time_function(p["time"]))
    return Case(
        name=f"manufactured_l_{body}", title=f"Manufactured motion of a {body} on an L-shaped mesh section",
        body=body, section=section, length=verification.LENGTH if body == PRISM else 2 * math.pi,
        material=material, regions=regions, loads=(),
        supports=(Support("outer", (1, 2, 3)), Support("notch", (1, 2, 3))),
        probes=tuple(Probe(f"u{c}", "point", "u", (c,), point=point) for c in (1, 2, 3)),
        params=dict(p, E=1.0, nu=verification.NU, rho=1.0, tau_s=math.inf, plastic=False),
        forces=forces(body, p["time"], p["a"]), exact=Motion(tuple(str(c) for c in motion(body)), time),
        variation=((p["a"], verification.VARIATION_MODE),) if p["a"] else (), symmetric=True,
        units="dimensionless (E = rho = 1)",
        provenance={"ours": "the whole scene: the L and its mesh, a chosen motion and the body force "
                            "that makes it exact"},
    )
