"""A solid disc of revolution that reaches the axis, its top edge rounded (examples/puck_strike.toml):
r in [0, 0.05], z in [0, 0.025] m, a fillet of radius 0.01 m at the top of the rim; unstructured
quad9 elements of about 0.01 m (three through the thickness), mid-side nodes on the fillet.

Physical curves: ``axis`` (r = 0), ``bottom`` (z = 0), ``patch`` (the top between r = 0.015 and
0.035, where the strike lands), ``free`` (the rest of the top, the fillet and the rim); surface
``steel``. Nodes at the probe points: the patch's middle (0.025, 0.025), the top and the bottom
on the axis. Run ``python -m cases.sections.puck [--size FACTOR]``.
"""

from cases.sections import meshing

NAME = "puck"
SIZE = 0.01  # m
RADIUS, HEIGHT, FILLET = 0.05, 0.025, 0.01  # m
PATCH = (0.015, 0.035)  # the strike's radii on the top, m
#: the probe points: the patch's middle, the top and the bottom on the axis
NODES_AT = ((0.5 * (PATCH[0] + PATCH[1]), HEIGHT), (0.0, HEIGHT), (0.0, 0.0))
#: the curves, numbered in this order
CURVES = ("axis", "bottom", "patch", "free")
#: triangles paired by the simple recombination: the Blossom default left a sliver where the
#: fillet meets the top (Jacobian ratio 0.001 against 0.357)
OPTIONS = {"Mesh.RecombinationAlgorithm": 0}


def geometry(gmsh, size: float) -> tuple[dict, dict]:
    """The section's boundary counter-clockwise from the axis at the bottom; the patch's middle
    is a point of its curve, so that a node stands there."""
    middle = 0.5 * sum(PATCH)
    # (curve name, end point, centre of the arc or None for a straight piece), each piece from
    # the end of the one before; the last closes the loop at the first corner
    pieces = [("bottom", (RADIUS, 0.0), None), ("free", (RADIUS, HEIGHT - FILLET), None),
              ("free", (RADIUS - FILLET, HEIGHT), (RADIUS - FILLET, HEIGHT - FILLET)),
              ("free", (PATCH[1], HEIGHT), None), ("patch", (middle, HEIGHT), None),
              ("patch", (PATCH[0], HEIGHT), None), ("free", (0.0, HEIGHT), None), ("axis", (0.0, 0.0), None)]
    named, steel = meshing.outline(gmsh, pieces, CURVES, size)
    return named, {"steel": [steel]}


if __name__ == "__main__":
    meshing.run(NAME, geometry, SIZE, NODES_AT, OPTIONS)
