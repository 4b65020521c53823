"""The rod's section (:mod:`cases.rod_impact`): r in [0, RADIUS], z in [0, LENGTH], unstructured
quad9 elements of size 0.01 m (about five across the radius).

Physical curves: ``axis`` (r = 0, split at z = LENGTH / 2 so the mid_szz probe is a node),
``lateral`` (r = RADIUS), ``face`` (z = 0, the struck face), ``free_end`` (z = LENGTH); surface
``steel``. Run ``python -m cases.sections.rod_impact [--size FACTOR]``.
"""

from cases.rod_impact import LENGTH, RADIUS
from cases.sections import meshing

NAME = "rod_impact"
SIZE = 0.01  # m
#: nodes the probes read: the rim of the face, the axis at mid-length
NODES_AT = ((RADIUS, 0.0), (0.0, LENGTH / 2))
#: triangles paired by the simple recombination: on this rectangle they make nearly square quads
#: (Jacobian ratio > 0.9; the Blossom default leaves some at 0.35)
OPTIONS = {"Mesh.RecombinationAlgorithm": 0}


def geometry(gmsh, size: float) -> tuple[dict, dict]:
    """The rectangle, its boundary counter-clockwise from the axis at the face."""
    occ = gmsh.model.occ
    corners = [(0.0, 0.0), (RADIUS, 0.0), (RADIUS, LENGTH), (0.0, LENGTH), (0.0, LENGTH / 2)]
    p = [occ.addPoint(x, y, 0.0, size) for x, y in corners]
    loop = [occ.addLine(a, b) for a, b in zip(p, p[1:] + p[:1])]
    face, lateral, free_end, *axis = loop
    steel = occ.addPlaneSurface([occ.addCurveLoop(loop)])
    curves = {"axis": axis, "lateral": [lateral], "face": [face], "free_end": [free_end]}
    return curves, {"steel": [steel]}


if __name__ == "__main__":
    meshing.run(NAME, geometry, SIZE, NODES_AT, OPTIONS)
