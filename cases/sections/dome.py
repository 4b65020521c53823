"""The dome's shell section (:mod:`cases.dome`, inches): the annular sector s in
[R - H/2, R + H/2], t in [0, alpha] mapped to (x1, x2) = (s sin t, s cos t), unstructured quad9
elements of size H/4 (about four through the thickness).

Physical curves: ``inner`` (s = R - H/2), ``outer`` (s = R + H/2, the loaded surface), ``axis``
(t = 0, x1 = 0, split at the mid-surface so the apex probe is a node), ``clamped`` (t = alpha);
surface ``shell``. Run ``python -m cases.sections.dome [--size FACTOR]``.
"""

import math

from cases.dome import HALF_ANGLE_DEG, H, R
from cases.sections import meshing

NAME = "dome"
SIZE = H / 4  # in
ALPHA = math.radians(HALF_ANGLE_DEG)
#: the apex on the mid-surface (the apex_uz probe)
NODES_AT = ((0.0, R),)


def geometry(gmsh, size: float) -> tuple[dict, dict]:
    """The sector, its boundary counter-clockwise: down the axis, along the inner arc, across
    the clamped edge, back along the outer arc."""
    occ = gmsh.model.occ
    inner_radius, outer_radius = R - H / 2, R + H / 2
    top, apex, bottom = (occ.addPoint(0.0, y, 0.0, size) for y in (outer_radius, R, inner_radius))
    inner_end, outer_end = (occ.addPoint(s * math.sin(ALPHA), s * math.cos(ALPHA), 0.0, size)
                            for s in (inner_radius, outer_radius))
    centre = occ.addPoint(0.0, 0.0, 0.0)
    axis = [occ.addLine(top, apex), occ.addLine(apex, bottom)]
    inner = occ.addCircleArc(bottom, centre, inner_end)
    clamped = occ.addLine(inner_end, outer_end)
    outer = occ.addCircleArc(outer_end, centre, top)
    shell = occ.addPlaneSurface([occ.addCurveLoop([*axis, inner, clamped, outer])])
    occ.remove([(0, centre)])  # the arcs' centre is not part of the section
    curves = {"inner": [inner], "outer": [outer], "axis": axis, "clamped": [clamped]}
    return curves, {"shell": [shell]}


if __name__ == "__main__":
    meshing.run(NAME, geometry, SIZE, NODES_AT)
