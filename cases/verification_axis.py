"""The manufactured scene of a solid of revolution that reaches the axis, on an unstructured
mesh section: code verification of a section with an edge on the axis (SMFEM's axis rows, the
3D reference's hexahedra degenerate there, :mod:`reference_fem.ties`).

The section is the unit square r in [0, 1], z in [0, 1], made of a few convex polygons (a
pentagon, quadrilaterals, a triangle) each split into quadrilaterals round its centroid
(:func:`cases.verification_mesh.subdivide`: corners of valence 3 and 5, elements on the axis that
are not rectangles), written as a gmsh file (:func:`write`) with the physical curves ``axis``
(r = 0) and ``outer`` (the other three edges), fixed; and refined by splitting every element
k x k (``refine = k``). The motion is a smooth *Cartesian* field turned into cylindrical
components (:func:`motion`), so it is regular on the axis as every physical motion is: harmonic
0 (u_r = B r, u_z = B), harmonic 1 (the axis's lateral translation, u_r = B cos, u_theta =
-B sin, with u_z = B r cos / 2) and harmonic 2 (u_r = B r cos 2x3, u_theta = -B r sin 2x3),
where ``B = (1 - r^2) 4 z (1 - z) exp((r^2 + z) / 2)`` vanishes on the fixed edges and is smooth
through the axis (a function of r^2). Nothing vanishes on the axis: the motion crosses it.
"""

from __future__ import annotations

import math
from functools import cache

import meshio
import numpy as np
import sympy as sp

from . import manufactured as mf
from .case import Case
from .geometry import RING, Motion, Probe, Support
from .material import Material
from .verification import NU, probe_histories, time_function
from .verification_mesh import boundary_lines, subdivide

#: the square's polygons: its corners, the middles of its sides, two interior points
POINTS = np.array([(0, 0), (0.5, 0), (1, 0), (1, 0.5), (1, 1), (0.5, 1), (0, 1), (0, 0.5), (0.4, 0.35), (0.6, 0.7)])
POLYGONS = ((0, 1, 8, 7), (1, 2, 3, 8), (8, 3, 9), (3, 4, 5, 9), (7, 8, 9, 5, 6))
#: probes: on the axis (r = 0) and off it, as (r, z, x3); nodes of every refined mesh
PROBES = {"axis_uz": ((0.0, 0.5, 0.0), 2), "axis_ux": ((0.0, 0.5, 0.0), 1), "ring_ur": ((0.5, 0.5, math.pi / 4), 1)}
DEFAULTS = dict(dt=2.5e-3, t_end=1.0, refine=1, harmonics=4, dim=2, time="cos", tol=1e-5)


def write(path):
    """The square's quad4 mesh as a gmsh file (MSH 2.2) at ``path``: physical curves ``axis`` and
    ``outer``, surface ``body``. Returns ``path``."""
    x, quads, _ = subdivide(POINTS, POLYGONS)
    lines = boundary_lines(quads)
    on_axis = np.all(np.abs(x[lines, 0]) < 1e-12, axis=1)
    blocks = [("line", lines[on_axis], 1), ("line", lines[~on_axis], 2), ("quad", quads, 3)]
    names = {"axis": [1, 1], "outer": [2, 1], "body": [3, 2]}
    tags = [np.full(len(cells), tag) for _, cells, tag in blocks]
    mesh = meshio.Mesh(np.column_stack([x, np.zeros(len(x))]), [(kind, cells) for kind, cells, _ in blocks],
                       cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
                       field_data={name: np.array(v) for name, v in names.items()})
    meshio.write(path, mesh, file_format="gmsh22", binary=False)
    return path


def motion() -> list[sp.Expr]:
    """``U(r, z, x3)`` in cylindrical components (u_r, u_z, u_theta): the Cartesian field
    ``(u_x, u_y, u_z) = B (1 + 2 x, 0, 1 + x / 2)`` (x = r cos x3; harmonics 0, 1, 2), B smooth
    through the axis."""
    r, z, th = mf.X1, mf.X2, mf.X3
    bubble = (1 - r**2) * 4 * z * (1 - z) * sp.exp((r**2 + z) / 2)
    u_r = bubble * (r + sp.cos(th) + r * sp.cos(2 * th))
    u_theta = bubble * (-sp.sin(th) - r * sp.sin(2 * th))
    u_z = bubble * (1 + r * sp.cos(th) / 2)
    return [u_r, u_z, u_theta]


@cache
def forces(time: str) -> tuple:
    """The body-force terms that make :func:`motion` times the time function exact, one
    displacement component at a time (derived once per time function)."""
    U, g = motion(), time_function(time)
    one_by_one = ([c if j == i else 0 for j, c in enumerate(U)] for i in range(3))
    return tuple(term for Ui in one_by_one for term in mf.motion_body_forces(Ui, g, RING, 1, NU, 1))


def build(section, params: dict | None = None) -> Case:
    """The scene on ``section`` (the square read from :func:`write`'s file) at ``params`` (over
    :data:`DEFAULTS`; ``element``, ``theta_elements`` as any scene's)."""
    p = {**DEFAULTS, **(params or {})}
    time = str(time_function(p["time"]))
    return Case(
        name="manufactured_axis", title="Manufactured motion of a solid of revolution through its axis",
        body=RING, section=section, length=2 * math.pi, material=Material(1.0, NU, 1.0), loads=(),
        supports=(Support("outer", (1, 2, 3)),),
        probes=tuple(Probe(name, "point", "u", (c,), point=point) for name, (point, c) in PROBES.items()),
        params=dict(p, E=1.0, nu=NU, rho=1.0, tau_s=math.inf, plastic=False),
        forces=forces(p["time"]), exact=Motion(tuple(str(c) for c in motion()), time), symmetric=True,
        units="dimensionless (E = rho = 1)",
        provenance={"ours": "the whole scene: the section and its mesh, a chosen motion regular on the axis and "
                            "the body force that makes it exact"},
    )


def exact(case, t: np.ndarray) -> dict[str, np.ndarray]:
    """The probes' exact histories at times ``t``."""
    return probe_histories(case.probes, motion(), time_function(case.params.get("time", DEFAULTS["time"])), t)
