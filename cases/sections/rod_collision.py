"""The two rods of :mod:`cases.rod_collision` as one section of two bodies: the striker r in
[0, RADIUS], z in [-STRIKER, 0] and the target r in [0, RADIUS], z in [0, TARGET], unstructured
quad9 elements of size 0.01 m (about five across the radius).

The rods are two OCC surfaces that do not share the line z = 0 where they touch, so each body
has its own nodes there (two rows at the same places: a mesh section of two bodies); the two
faces are transfinite curves of one node count, so that their nodes face each other node for
node, as a contact pair needs.

Physical curves, named ``body.edge`` as the built-in scene's edges: ``striker.axis``,
``striker.lateral``, ``striker.end`` (z = -STRIKER), ``striker.face`` (z = 0), ``target.face``
(z = 0), ``target.lateral``, ``target.end`` (z = TARGET), ``target.axis`` (split at mid-length
so the target_mid_szz probe is a node); surfaces ``striker`` and ``target``. Run
``python -m cases.sections.rod_collision [--size FACTOR]``.
"""

import math

from cases.rod_collision import RADIUS, STRIKER, TARGET
from cases.sections import meshing

NAME = "rod_collision"
SIZE = 0.01  # m
#: nodes the probes read: the target's axis at mid-length and at its free end
NODES_AT = ((0.0, TARGET / 2), (0.0, TARGET))
#: triangles paired by the simple recombination, as the rod's (nearly square quads)
OPTIONS = {"Mesh.RecombinationAlgorithm": 0}


def geometry(gmsh, size: float) -> tuple[dict, dict]:
    """The two rectangles, each bounded counter-clockwise from its axis at z = 0 (the face)."""
    occ = gmsh.model.occ

    def rod(name: str, z0: float, z1: float, axis_breaks: tuple = ()) -> tuple[dict, list]:
        corners = [(0.0, z0), (RADIUS, z0), (RADIUS, z1), (0.0, z1)] + [(0.0, z) for z in axis_breaks]
        p = [occ.addPoint(x, y, 0.0, size) for x, y in corners]
        loop = [occ.addLine(a, b) for a, b in zip(p, p[1:] + p[:1])]
        bottom, lateral, top, *axis = loop
        surface = occ.addPlaneSurface([occ.addCurveLoop(loop)])
        face, end = (top, bottom) if z1 == 0.0 else (bottom, top)
        names = {"axis": axis, "lateral": [lateral], "face": [face], "end": [end]}
        return {f"{name}.{edge}": tags for edge, tags in names.items()}, [surface]

    striker, striker_surface = rod("striker", -STRIKER, 0.0)
    target, target_surface = rod("target", 0.0, TARGET, (TARGET / 2,))
    occ.synchronize()
    # the faces node for node: the same count on each, the size's across the radius
    across = math.ceil(RADIUS / size - 1e-9) + 1
    for face in striker["striker.face"] + target["target.face"]:
        gmsh.model.mesh.setTransfiniteCurve(face, across)
    return striker | target, {"striker": striker_surface, "target": target_surface}


if __name__ == "__main__":
    meshing.run(NAME, geometry, SIZE, NODES_AT, OPTIONS)
