"""What the section scripts share: the gmsh options that make unstructured 9-node quadrilaterals,
the physical groups, the ``.msh`` file, and the check of that file as meshio reads it.

A script gives a geometry function ``geometry(gmsh, size) -> (curves, surfaces)`` that builds
the section with ``gmsh.model.occ`` in the x-y plane (x = x1, y = x2) and returns the tags of its
named curves and surfaces (dicts ``name -> list of tags``, in the order the groups are numbered).
gmsh is imported only in :func:`main`, so the modules import without it.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path
from typing import Callable

import meshio
import numpy as np

MISSING_GMSH = "making section meshes needs gmsh: pip install '.[gmsh]'"
HERE = Path(__file__).resolve().parent
#: gmsh options of every section: Frontal-Delaunay for quads, recombined by the Blossom
#: algorithm, complete quadratic elements, physical groups only; one thread, so that each run
#: writes the same file
OPTIONS = {
    "General.Terminal": 0, "General.NumThreads": 1,
    "Mesh.Algorithm": 8, "Mesh.RecombineAll": 1, "Mesh.RecombinationAlgorithm": 1,
    "Mesh.SecondOrderIncomplete": 0,
    "Mesh.MshFileVersion": 2.2, "Mesh.Binary": 0, "Mesh.SaveAll": 0,
}
#: gmsh's element type number of the 3-node triangle
TRIANGLE = 2
Point = tuple[float, float]

#: the reference positions (in [-1, 1]) of gmsh's quad9 nodes: corners counter-clockwise, the
#: mid-sides of edges 0-1, 1-2, 2-3, 3-0, the centre
NODE_XI = np.array([-1, 1, 1, -1, 0, 1, 0, -1, 0])
NODE_ETA = np.array([-1, -1, 1, 1, -1, 0, 1, 0, 0])
#: where det J is sampled: a 5 x 5 grid over the element (its nodes and the points between)
SAMPLE_XI, SAMPLE_ETA = (a.ravel() for a in np.meshgrid(*2 * [np.linspace(-1, 1, 5)]))


def run(name: str, geometry: Callable, size: float, nodes_at: tuple[Point, ...] = (),
        options: dict | None = None) -> None:
    """The scripts' entry point: :func:`main` with the command line, exiting with its status."""
    sys.exit(main(name, geometry, size, sys.argv[1:], nodes_at, options))


def main(name: str, geometry: Callable, size: float, argv: list[str] | None = None,
         nodes_at: tuple[Point, ...] = (), options: dict | None = None) -> int:
    """Make ``cases/sections/<name>.msh`` from ``geometry`` at element size ``size`` times
    ``--size`` with gmsh ``options`` over :data:`OPTIONS`, check it (:func:`summary`, and a node
    at each of ``nodes_at``), print one line; the file is replaced only by a mesh that passes.

    Returns the exit status: 0, or 2 without the gmsh package.
    """
    parser = argparse.ArgumentParser(prog=f"python -m cases.sections.{name}",
                                     description=f"Write cases/sections/{name}.msh with gmsh.")
    parser.add_argument("--size", type=positive, default=1.0, metavar="FACTOR",
                        help=f"scale the element size (default 1: {size:g})")
    args = parser.parse_args(argv)
    try:
        import gmsh
    except ImportError:
        print(MISSING_GMSH)
        return 2
    # made beside the kept file and moved over it once it passes: a failed mesh is not kept
    with tempfile.TemporaryDirectory(dir=HERE) as scratch:
        made = Path(scratch) / f"{name}.msh"
        write(gmsh, name, geometry, size * args.size, made, options or {})
        line = summary(made, nodes_at)
        made.replace(HERE / made.name)
    print(line)
    return 0


def outline(gmsh, pieces, names, size: float) -> tuple[dict, int]:
    """A section bounded by one loop of straight lines and circular arcs: ``pieces`` is a list of
    ``(curve name, end point, centre of the arc or None for a straight piece)``, each from the
    end of the one before, the last closing the loop at the first's start. Returns the curve
    tags by name (``names``, in their order) and the plane surface's tag."""
    occ = gmsh.model.occ
    points = [occ.addPoint(x, y, 0.0, size) for _, (x, y), _ in pieces]
    named, loop, centres = {name: [] for name in names}, [], []
    for (name, _, centre), a, b in zip(pieces, points[-1:] + points[:-1], points):
        if centre is None:
            loop.append(occ.addLine(a, b))
        else:
            centres.append(occ.addPoint(*centre, 0.0))
            loop.append(occ.addCircleArc(a, centres[-1], b))
        named[name].append(loop[-1])
    surface = occ.addPlaneSurface([occ.addCurveLoop(loop)])
    occ.remove([(0, c) for c in centres])  # the arcs' centres are not part of the section
    return named, surface


def positive(text: str) -> float:
    """``--size``'s value: a finite number > 0."""
    value = float(text)
    if not 0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"--size must be a finite number > 0, not {text}")
    return value


def write(gmsh, name: str, geometry: Callable, size: float, path: Path, options: dict) -> None:
    """Mesh the section with quad9 elements (mid-side nodes on the curved geometry) and save
    its physical groups only, MSH 2.2 ASCII.

    Where recombination leaves triangles (an odd number of edges around a face leaves one),
    the section is meshed again twice as coarse and every element split into quadrilaterals.
    """
    gmsh.initialize(readConfigFiles=False)  # no user options: the file depends on this code only
    try:
        for option, value in {**OPTIONS, "Mesh.MeshSizeMax": size, **options}.items():
            gmsh.option.setNumber(option, value)
        gmsh.model.add(name)
        curves, surfaces = geometry(gmsh, size)
        gmsh.model.occ.synchronize()
        groups = [(1, group, tags) for group, tags in curves.items()]
        groups += [(2, group, tags) for group, tags in surfaces.items()]
        for tag, (dim, group, tags) in enumerate(groups, start=1):
            gmsh.model.addPhysicalGroup(dim, tags, tag, name=group)
        gmsh.model.mesh.generate(2)
        if TRIANGLE in gmsh.model.mesh.getElementTypes(2):
            gmsh.model.mesh.clear()
            split = {"Mesh.SubdivisionAlgorithm": 1, "Mesh.MeshSizeFactor": 2,
                     "Mesh.MeshSizeMax": 2 * size}
            for option, value in split.items():
                gmsh.option.setNumber(option, value)
            gmsh.model.mesh.generate(2)
        gmsh.model.mesh.setOrder(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


def summary(path: Path, nodes_at: tuple[Point, ...] = ()) -> str:
    """One line on the mesh in ``path`` after checking it as meshio reads it: 2-D cells all
    ``quad9`` with a positive Jacobian everywhere (counter-clockwise), curves ``line3``, every
    physical name in ``field_data`` with cells, every node used, a node at each of ``nodes_at``.

    The element size is the range of the corner-to-corner edge lengths; the Jacobian ratio of
    an element is min/max of det J over a 5 x 5 grid of points in it.
    """
    mesh = meshio.read(path, file_format="gmsh")  # ".msh" alone tries ANSYS first and prints
    types = {block.type for block in mesh.cells}
    if types != {"quad9", "line3"}:
        raise ValueError(f"{path.name}: cells {sorted(types)}, not quad9 and line3 only")
    tags = np.concatenate(mesh.cell_data["gmsh:physical"])
    empty = [n for n, (tag, _) in mesh.field_data.items() if not np.any(tags == tag)]
    if empty:
        raise ValueError(f"{path.name}: physical groups {empty} have no cells")
    used = np.unique(np.concatenate([block.data.ravel() for block in mesh.cells]))
    if len(used) != len(mesh.points):
        raise ValueError(f"{path.name}: {len(mesh.points) - len(used)} nodes belong to no element")
    missing = [p for p in nodes_at if np.min(np.hypot(*(mesh.points[:, :2] - p).T)) > 1e-12]
    if missing:
        raise ValueError(f"{path.name}: no node at {missing}")
    quads = mesh.get_cells_type("quad9")
    det = jacobians(mesh.points[quads, :2])
    wrong = np.sum(np.any(det <= 0, axis=1))
    if wrong:
        raise ValueError(f"{path.name}: {wrong} elements are not counter-clockwise")
    corners = mesh.points[quads[:, :4], :2]
    edges = np.linalg.norm(np.roll(corners, -1, axis=1) - corners, axis=-1)
    ratio = np.min(det, axis=1) / np.max(det, axis=1)
    kinds = {1: "curve", 2: "surface"}
    names = ", ".join(f"{n} ({kinds[dim]})" for n, (_, dim) in mesh.field_data.items())
    return (f"{path.name}: {len(quads)} quad9, {len(mesh.points)} nodes, element size "
            f"{edges.min():.4g} .. {edges.max():.4g}, min Jacobian ratio {ratio.min():.3f}; "
            f"{names}")


def jacobians(X: np.ndarray) -> np.ndarray:
    """det J of quad9 elements with nodes ``X (n_elements, 9, 2)`` at the sample points:
    ``(n_elements, 25)``."""
    dxi, deta = shape_derivatives(SAMPLE_XI, SAMPLE_ETA)
    J = np.stack([np.einsum("pn,enc->epc", dxi, X), np.einsum("pn,enc->epc", deta, X)], axis=-1)
    return np.linalg.det(J)


def shape_derivatives(xi: np.ndarray, eta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """dN/dxi and dN/deta of the biquadratic quad9 functions at points ``(xi, eta)``:
    two ``(n_points, 9)``."""

    def lagrange(s):  # quadratic functions at -1, 0, 1 and their derivatives, (n, 3) each
        s = s[:, None]
        return (np.hstack([s * (s - 1) / 2, 1 - s * s, s * (s + 1) / 2]),
                np.hstack([s - 0.5, -2 * s, s + 0.5]))

    (a, da), (b, db) = lagrange(np.asarray(xi, float)), lagrange(np.asarray(eta, float))
    i, j = NODE_XI + 1, NODE_ETA + 1
    return da[:, i] * b[:, j], a[:, i] * db[:, j]
