"""The flywheel's section: a disk of revolution in (r, z) with a hub, a thin web and a rim,
filleted where the web meets them; unstructured quad9 elements of size 0.005 m (about four
through the 0.02 m web), half that on the fillets.

Hub r in [0.05, 0.10], z in [-0.04, 0.04]; web r in [0.10, 0.25], z in [-0.01, 0.01]; rim
r in [0.25, 0.30], z in [-0.03, 0.03]; fillets of radius 0.01 m in the four concave corners.
Physical curves: ``bore`` (r = 0.05), ``rim_top`` (z = 0.03), ``rim_outer`` (r = 0.30),
``rim_bottom`` (z = -0.03), ``fillets`` (the four arcs), ``free`` (the rest of the boundary);
surface ``steel``. Run ``python -m cases.sections.flywheel [--size FACTOR]``.
"""

from cases.sections import meshing

NAME = "flywheel"
SIZE = 0.005  # m
#: (inner radius, outer radius, half-height), m
HUB, WEB, RIM = (0.05, 0.10, 0.04), (0.10, 0.25, 0.01), (0.25, 0.30, 0.03)
FILLET = 0.01  # m
#: the physical curves, numbered 1 to 6 in this order
CURVES = ("bore", "rim_top", "rim_outer", "rim_bottom", "fillets", "free")
#: the rim's outer top corner, where loads and probes may sit
NODES_AT = ((RIM[1], RIM[2]),)
#: Blossom full-quad recombination: its worst element is better here than the default's
#: (Jacobian ratio 0.35 against 0.24)
OPTIONS = {"Mesh.RecombinationAlgorithm": 3}


def geometry(gmsh, size: float) -> tuple[dict, dict]:
    """The section's boundary counter-clockwise from the bore's bottom corner: straight pieces
    between corners, a quarter circle at each concave corner."""
    occ = gmsh.model.occ
    f, (hub_in, hub_out, hub_h), (rim_in, rim_out, rim_h), web_h = FILLET, HUB, RIM, WEB[2]
    # (curve name, end point, centre of the arc or None for a straight piece), each piece from
    # the end of the one before; the last closes the loop at the first corner
    pieces = [
        ("free", (hub_out, -hub_h), None), ("free", (hub_out, -web_h - f), None),
        ("fillets", (hub_out + f, -web_h), (hub_out + f, -web_h - f)),
        ("free", (rim_in - f, -web_h), None),
        ("fillets", (rim_in, -web_h - f), (rim_in - f, -web_h - f)),
        ("free", (rim_in, -rim_h), None), ("rim_bottom", (rim_out, -rim_h), None),
        ("rim_outer", (rim_out, rim_h), None), ("rim_top", (rim_in, rim_h), None),
        ("free", (rim_in, web_h + f), None),
        ("fillets", (rim_in - f, web_h), (rim_in - f, web_h + f)),
        ("free", (hub_out + f, web_h), None),
        ("fillets", (hub_out, web_h + f), (hub_out + f, web_h + f)),
        ("free", (hub_out, hub_h), None), ("free", (hub_in, hub_h), None),
        ("bore", (hub_in, -hub_h), None),
    ]
    named, steel = meshing.outline(gmsh, pieces, CURVES, size)
    refine_near(gmsh, named["fillets"], size)
    return named, {"steel": [steel]}


def refine_near(gmsh, fillets: list[int], size: float) -> None:
    """Element size ``size / 2`` on the fillets, growing to ``size`` one fillet radius away (a
    finer size at their end points alone would spread along the web and halve it throughout)."""
    gmsh.model.occ.synchronize()
    field = gmsh.model.mesh.field
    distance = field.add("Distance")
    field.setNumbers(distance, "CurvesList", fillets)
    field.setNumber(distance, "Sampling", 50)
    threshold = field.add("Threshold")
    field.setNumber(threshold, "InField", distance)
    limits = {"SizeMin": size / 2, "SizeMax": size, "DistMin": 0.0, "DistMax": FILLET}
    for option, value in limits.items():
        field.setNumber(threshold, option, value)
    field.setAsBackgroundMesh(threshold)


if __name__ == "__main__":
    meshing.run(NAME, geometry, SIZE, NODES_AT, OPTIONS)
