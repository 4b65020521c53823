"""A case as an Abaqus/CalculiX input deck (``.inp``) on the reference FEM's mesh.

The procedure (:mod:`.procedures`) picks the elements: for the implicit and modal ones the mesh's
quadratic Lagrange elements lose their face and centre nodes and become serendipity elements
(CPE8 plane strain, CAX8 axisymmetric (x = r, y = z) or C3D20); for the explicit one each is
split into linear elements on the same nodes (CPE4, CAX4 or C3D8, :mod:`.linear`). Everything
else is the case's: the elastic material, von Mises plasticity as a table (ideal, or linear
isotropic hardening), a material and a solid section per region of another material (on the
element set of its elements), the loads under their amplitudes (:mod:`.loads`: pressures as
element-face loads, a moving one per facet, force terms as nodal forces), the reference's
supports (so the same dofs are fixed), the initial velocity and the procedure's step. A run's
deck writes only what its probes read (:func:`output_cards`); an exported one (``fields``)
the fields at every increment too. A rigid wall is a unilateral gap element (GAPUNI) from each
node of the struck face to a fixed ground node, with the spring of the case's contact layer
(exported for the user; :mod:`.solver` does not solve wall scenes).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from cases.material import ELASTIC, VON_MISES
from cases.params import UnsupportedCase

from .. import ties
from ..face import plane_face
from ..frames import AXISYMMETRIC, SOLID, body_point_to_mesh
from ..mesh import vtk_cells
from ..model import Model
from .courant import output_frequency, stable_increment, wave_speed
from .linear import face_children, split
from .loads import Amplitudes, force_cards, pressure_cards, refuse_early, serendipity_forces
from .procedures import EXPLICIT, IMPLICIT, MODAL, MODES, check_modes, element, fixed_increments, linear, refuse, step_cards

#: corner nodes (0-based, in the element's order) of each face P1 ... of CPE8/CAX8 and C3D20
FACES = {
    2: ((0, 1), (1, 2), (2, 3), (3, 0)),
    3: ((0, 1, 2, 3), (4, 7, 6, 5), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)),
}
#: nodes of the serendipity element (its corners and mid-sides) by mesh dimension
CORNERS = {2: 8, 3: 20}
PER_LINE = 8  # numbers per data line (Abaqus allows 16; short lines read better)


@dataclass
class Deck:
    """An input deck and what reading its results needs.

    Attributes
    ----------
    text : the ``.inp`` file
    element : ``'CPE8'``, ``'CAX8'``, ``'C3D20'`` (serendipity) or ``'CPE4'``, ``'CAX4'``,
        ``'C3D8'`` (linear)
    points : mesh-frame coordinates of every node of the reference mesh, ``(dim, n)``; node
        ``k`` of the deck is ``k + 1`` (a serendipity deck leaves the Lagrange face and centre
        nodes out)
    cells : the reference mesh's cells (VTK quad9 / hexahedron27 order), ``(n_cells, 9 | 27)``
    elements : the deck's elements by their nodes (0-based), ``(n_elements, 4 | 8 | 20)``
    model : the reference model the deck was made from (supports, mass, faces)
    probe_nodes : probe name -> deck node at the probe point (point probes only)
    procedure : :data:`.procedures.PROCEDURES`
    increment : the explicit procedure's predicted increment (:mod:`.courant`; 0 for the others)
    every : increments between the .frd's outputs (an explicit step's from its predicted increment)
    """

    text: str
    element: str
    points: np.ndarray
    cells: np.ndarray
    elements: np.ndarray
    model: Model
    probe_nodes: dict = field(default_factory=dict)
    frd_bytes: float = 0.0
    procedure: str = IMPLICIT
    increment: float = 0.0
    every: int = 1

    @property
    def nodes(self) -> np.ndarray:
        """The deck's nodes (0-based), sorted."""
        return np.unique(self.elements)

    @property
    def serendipity(self) -> bool:
        """Its elements leave the Lagrange face and centre nodes out (:func:`.solver.complete`)."""
        return not linear(self.procedure)


#: characters of one node's line in an ASCII .frd block of ``c`` components (" -1", the node
#: number, 12 characters per value): with these the dome's .frd (200 increments, 369 nodes,
#: DISP, VELO, STRESS and its ERROR) is estimated at 13.4 MB against 12.5 MB written by ccx 2.20,
#: the notched strip's at 115 MB against 101 MB
FRD_LINE = (13, 12)
#: increments per step of ccx's own stepping (plastic runs), measured on the notched strip: 118 for 100
OWN_INCREMENTS = 1.2


def frd_size(case, n_nodes: int, every: int = 1, outputs: float | None = None) -> float:
    """Bytes of the .frd the deck makes ccx write (its ``*NODE FILE`` and ``*EL FILE`` blocks,
    every ``every`` increments, or ``outputs`` times in all): an estimate, for a warning before
    a long run."""
    blocks = [4, 4, 6, 1] + ([1] if case.material.plastic else []) + ([4] if case.wall is not None else [])
    increments = outputs or case.n_steps * (1.0 if fixed_increments(case) else OWN_INCREMENTS) / every
    return increments * n_nodes * sum(FRD_LINE[0] + FRD_LINE[1] * c for c in blocks)


#: why contact between bodies is not solved in CalculiX (measured on rod_collision, issue 39)
CONTACT_PAIRS_REFUSED = (
    "calculix: contact between bodies is not solved: in ccx 2.20's implicit dynamics a *CONTACT PAIR stops at "
    "the second increment (its impact rule, hard-coded energy thresholds that fixed increments cannot pass), and "
    "gap elements between the facing nodes at the layer's stiffness grow without bound (the faces keep their mass); "
    "both run only 100 times softer, which is not the scene")


def build_deck(case, every: int = 1, procedure: str = IMPLICIT, modes: int | None = None,
               fields: bool = True) -> Deck:
    """The deck of ``case`` at its parameters (``dim`` 2 or 3, ``refine``, ``dt``, ``t_end``)
    run by ``procedure`` (:mod:`.procedures`; ``modes``: the modal one's mode count); with
    ``fields`` (``smfem export``) the fields written to the .frd every ``every`` increments, else
    only what the probes read (``smfem run --solver calculix``)."""
    refuse(case, procedure, modes)
    if case.wall is not None and case.wall.slope:
        raise UnsupportedCase("calculix: a tilted wall (wall_slope > 0) is not exported; use wall_slope=0")
    if case.wall is not None and case.material.plastic:
        raise UnsupportedCase("calculix: contact with plasticity is not exported (as in the reference FEM)")
    if case.contacts:
        raise UnsupportedCase(CONTACT_PAIRS_REFUSED)
    if any(p.region for p in case.probes):
        raise UnsupportedCase("calculix: a mean over one body (a probe's region) is not read back so far")
    for mat in case.materials:
        _law_cards(mat)
    if case.variation:
        raise UnsupportedCase("calculix: a material varying along x3 (variation) is not exported")
    refuse_early(case)
    model = Model(case)
    mesh, dim = model.rmesh.mesh, model.dim
    _, cells = vtk_cells(mesh)
    name = element(model.rep, procedure, any(m.plastic for m in case.materials))
    # a linear deck has every node; a serendipity one its cells' corners and mid-sides
    children = 2**dim if linear(procedure) else 1
    elements = split(cells) if children > 1 else cells[:, : CORNERS[dim]]
    used = np.unique(elements)
    increment = 0.0
    if procedure == EXPLICIT:  # ccx writes every increment: every how many to keep, from its increment
        speed = np.array([wave_speed(m) for m in case.materials])[np.repeat(model.material_index, children)]
        increment = stable_increment(np.asarray(model.nodes_x, float), elements, speed, name)
        every *= output_frequency(case.dt, increment)
    if procedure == MODAL:
        check_modes(modes or MODES, used.size * dim - np.isin(model.fixed // dim, used).sum())
    points = np.asarray(model.nodes_x, float)
    points = np.where(np.abs(points) < 1e-12 * np.abs(points).max(), 0.0, points)  # see _number
    out = [
        f"** {case.title}",
        f"** written by smfem export from case {case.name!r} with {_params(case)}",
        f"** units: {case.units}; element {name} on the reference FEM's mesh "
        f"({mesh.nelements} elements, refine {case.refine}" + (f", each split in {children})" if children > 1 else ")"),
        f"** procedure: {procedure}" + (f", {modes or MODES} modes" if procedure == MODAL else ""),
        "*HEADING",
        f"smfem case {case.name}",
        "*NODE, NSET=NALL",
        *(_row([k + 1, *(_number(x) for x in points[:, k])]) for k in used),
        f"*ELEMENT, TYPE={name}, ELSET=EALL",
        *(_row([e + 1, *(nodes + 1)]) for e, nodes in enumerate(elements)),
    ]
    if case.wall is not None:
        out += _wall(model, points, cells, name)
    out += _sections(case, model, children)
    out += _supports(model, used)
    out += _initial_velocity(case, model, used)
    probe_nodes = _probe_nodes(case, model, points, used)
    if probe_nodes:
        out += ["** probes (smfem's names): one node set each, P_<name>; all of them in PROBES",
                *(f"** {name}: node {node}" for name, node in probe_nodes.items()),
                *(line for name, node in probe_nodes.items() for line in (f"*NSET, NSET=P_{name.upper()}", f"{node}")),
                "*NSET, NSET=PROBES", *_rows(sorted(set(probe_nodes.values())))]
    # the loads first: what cannot be exported is refused before anything else is done
    amplitudes = Amplitudes(case.t_end)

    def faces(facets):
        return [(e * children + s, k) for e, k in _element_faces(model, cells, facets, dim)
                for s in (face_children(dim, k - 1, FACES[dim]) if children > 1 else (0,))]

    loads = pressure_cards(case, model, faces, amplitudes)
    # the reference's nodal forces: on every node of a linear deck, moved onto a serendipity one's
    loads += force_cards(case, model, amplitudes, (lambda F: F) if children > 1 else
                         (lambda F: serendipity_forces(F, cells, dim)))
    out += ["*AMPLITUDE, NAME=STEPLOAD", f"0., 1., {case.t_end:.13g}, 1.", *amplitudes.cards()]
    out += step_cards(case, procedure, modes)
    out += loads
    out += output_cards(case, dim, every) if fields else probe_output(case, dim, every)
    out += ["*END STEP", ""]
    outputs = case.t_end / (every * increment) if increment else None
    return Deck("\n".join(out), name, points, cells, elements, model, probe_nodes,
                frd_size(case, used.size, every, outputs) if fields else 0.0, procedure, increment, every)


def output_cards(case, dim: int, every: int) -> list[str]:
    """The fields every ``every`` increments (an exported deck's, for the user's post-processor)
    and the probes' displacements in the .dat."""
    node_out = "U, V" + (", RF" if case.wall is not None else "")
    el_out = "S" + (", PEEQ" if case.material.plastic else "")
    options = _output_options(dim, every)
    out = [f"*NODE FILE{options}", node_out, f"*EL FILE{options}", el_out]
    if any(p.kind == "point" for p in case.probes):
        out += ["*NODE PRINT, NSET=PROBES", "U"]
    return out


#: the .frd's result of each probe field, and whether it is a nodal (else an element) output
PROBE_RESULTS = {"u": ("U", True), "v": ("V", True), "sigma": ("S", False), "peps": ("PEEQ", False)}


def probe_output(case, dim: int, every: int = 1) -> list[str]:
    """What the probes read, each result once, on the probes' node set where every probe of it
    is a point probe, else on the whole body: a user timing ccx writes no more."""
    nodal, element_out = {}, {}
    for probe in case.probes:
        result, is_nodal = PROBE_RESULTS[probe.field]
        where = nodal if is_nodal else element_out
        where[result] = where.get(result, True) and probe.kind == "point"
    options = _output_options(dim, every)
    out = []
    for card, results in (("*NODE FILE", nodal), ("*EL FILE", element_out)):
        for on_probes in (True, False):
            chosen = [r for r, probes_only in results.items() if probes_only == on_probes]
            if chosen:
                out += [f"{card}{options}" + (", NSET=PROBES" if on_probes else ""), ", ".join(chosen)]
    return out


def _output_options(dim: int, every: int) -> str:
    """A 2D model's results on its own nodes (not the 3D expansion's), every ``every`` increments
    (ccx takes the last ``FREQUENCY`` for all its file output, so each card gets the same)."""
    return ("" if dim == 3 else ", OUTPUT=2D") + (f", FREQUENCY={every}" if every > 1 else "")


def _params(case) -> str:
    return ", ".join(f"{k}={v}" for k, v in case.params.items())


def _number(x: float) -> str:
    """A number in 13 significant digits (coordinates: round-off zeros are zeroed before, as ccx
    misread values such as 2.44929359829471e-16 into nonpositive Jacobians)."""
    return f"{x:.13g}"


def _row(values) -> str:
    """One data line; longer ones continue on the next (a line ending in a comma)."""
    text = [str(v) for v in values]
    chunks = [", ".join(text[i : i + 16]) for i in range(0, len(text), 16)]
    return ",\n".join(chunks)


def _rows(values) -> list[str]:
    values = [str(v) for v in values]
    return [", ".join(values[i : i + PER_LINE]) + "," for i in range(0, len(values), PER_LINE)]


def _elastic_cards(mat) -> list[str]:
    return ["*ELASTIC", f"{mat.E:.13g}, {mat.nu:.13g}"]


def _von_mises_cards(mat) -> list[str]:
    """von Mises, isotropic hardening: sigma_y(eps_p) = sigma_y0 + H eps_p, as a table."""
    lines = _elastic_cards(mat) + ["*PLASTIC", f"{mat.sigma_y:.13g}, 0."]
    if mat.E_T:
        lines.append(f"{mat.sigma_y + mat.hardening_modulus:.13g}, 1.")
    return lines


#: the material law's name (:attr:`cases.material.Material.law`) -> its cards
LAW_CARDS = {ELASTIC: _elastic_cards, VON_MISES: _von_mises_cards}


def _law_cards(mat):
    """The cards of ``mat``'s law; a law without cards is refused before anything is written."""
    cards = LAW_CARDS.get(mat.law)
    if cards is None:
        raise UnsupportedCase(f"calculix: material law {mat.law!r} is not exported (its laws: {', '.join(LAW_CARDS)})")
    return cards


def _material(mat, name: str) -> list[str]:
    return [f"*MATERIAL, NAME={name}", "*DENSITY", f"{mat.rho:.13g}", *_law_cards(mat)(mat)]


def _region_names(case) -> list[str]:
    """The deck's name of each region's material and element set: its name in capitals, its
    characters other than letters, digits and ``_`` made ``_``, prefixed ``MAT_`` and ``E_``
    (``case.material`` is ``MAT`` on ``EALL``, or on ``EBASE`` beside regions)."""
    names = ["".join(ch if ch.isalnum() or ch == "_" else "_" for ch in r.name.upper()) for r in case.regions]
    if len(set(names)) < len(names) or any(len(n) > 70 for n in names):
        given = ", ".join(r.name for r in case.regions)
        raise UnsupportedCase(f"calculix: region names {given} are not distinct (in capitals, other characters "
                              "as _) or longer than 70 characters")
    return names


def _sections(case, model: Model, children: int = 1) -> list[str]:
    """The materials and their solid sections: ``MAT`` on every element (``EALL``), or with
    regions one ``*MATERIAL`` and one ``*SOLID SECTION`` on an ``*ELSET`` per material (an
    element set without elements is left out); ``children``: deck elements per reference cell."""
    thickness = "" if model.dim == 3 else "\n1."  # plane strain: per unit thickness; axisymmetric: ignored
    if not case.regions:
        return _material(case.material, "MAT") + [f"*SOLID SECTION, ELSET=EALL, MATERIAL=MAT{thickness}"]
    names = _region_names(case)
    out = []
    for k, (mat, material, elset) in enumerate(zip(case.materials, ["MAT"] + [f"MAT_{n}" for n in names],
                                                   ["EBASE"] + [f"E_{n}" for n in names])):
        out += _material(mat, material)
        cells = np.flatnonzero(model.material_index == k)
        elements = (cells[:, None] * children + np.arange(children)).ravel() + 1
        if elements.size:
            out += [f"*ELSET, ELSET={elset}", *_rows(elements),
                    f"*SOLID SECTION, ELSET={elset}, MATERIAL={material}{thickness}"]
    return out


def _supports(model: Model, used: np.ndarray) -> list[str]:
    """The reference's fixed dofs (supports, diaphragm ends, the axis) as ``*BOUNDARY`` lines."""
    node, comp = np.divmod(model.fixed, model.dim)
    keep = np.isin(node, used)
    if not keep.any():
        return []
    return ["*BOUNDARY", *(f"{n + 1}, {c + 1}, {c + 1}" for n, c in zip(node[keep], comp[keep]))]


def _initial_velocity(case, model: Model, used: np.ndarray) -> list[str]:
    """The initial velocity at every node. CalculiX 2.20 does not carry the initial velocity of a
    2D (CPE8/CAX8) node over to the nodes of the element's 3D expansion (later versions map it in
    gen3dtemp.f): the body would start at rest. A massless point-mass element at each 2D node makes
    ccx tie the expansion to that node (gen3dconnect.f), which then governs and keeps its velocity."""
    if not case.initial_velocity:
        return []
    v = model.initial_velocity().reshape(-1, model.dim)
    lines = []
    if model.dim == 2:
        first = model.rmesh.mesh.nelements + v.shape[0] + 1  # after the body's and any wall's elements
        lines += ["*ELEMENT, TYPE=MASS, ELSET=CARRIERS", *(f"{first + j}, {n + 1}" for j, n in enumerate(used)),
                  "*MASS, ELSET=CARRIERS", "0."]
    lines += ["*INITIAL CONDITIONS, TYPE=VELOCITY"]
    for n in used:
        lines += [f"{n + 1}, {c + 1}, {v[n, c]:.13g}" for c in range(model.dim) if v[n, c] != 0.0]
    return lines


def _probe_nodes(case, model: Model, points: np.ndarray, used: np.ndarray) -> dict:
    """The deck node at each point probe. CalculiX reports at nodes, so a probe must sit on
    one (to 1e-4 of the body's size: the printed peps_A radius 1.0333 is the node at 1 + 1/30);
    a probe between nodes is refused, not interpolated."""
    size = np.abs(points).max()
    nodes = {}
    for probe in case.probes:
        if probe.kind != "point":
            continue
        x = body_point_to_mesh(case, model.rep, probe.point)
        d = np.linalg.norm(points[:, used] - x[:, None], axis=0)
        k = int(np.argmin(d))
        if d[k] > 1e-4 * size:
            raise UnsupportedCase(f"calculix: probe {probe.name!r} at {probe.point} is not on a node of the "
                                  f"mesh (nearest {d[k]:.3g} away)")
        nodes[probe.name] = int(used[k]) + 1
    return nodes


def _element_faces(model: Model, cells: np.ndarray, facets: np.ndarray, dim: int) -> list[tuple[int, int]]:
    """``(element, face number 1...)`` of boundary ``facets``."""
    mesh = model.rmesh.mesh
    out = []
    for f in facets:
        e = int(mesh.f2t[0, f])
        corners = set(ties.of(mesh, mesh.facets[:, f]).tolist())  # as the cells name them
        for k, face in enumerate(FACES[dim]):
            if {int(cells[e, i]) for i in face} == corners:
                out.append((e, k + 1))
                break
        else:
            raise AssertionError(f"facet {f} is no face of element {e}")
    return out


def _wall(model: Model, points, cells, element: str) -> list[str]:
    """A rigid wall (2D): a unilateral gap element (GAPUNI) from each node of the struck face to a
    fixed ground node there, closing at the case's gap along the face's outward normal. Its spring
    is the case's thin contact layer (Young's modulus ``layer_stiffness * E``, thickness
    ``layer_thickness``): slope E_layer / t_layer per unit area times the node's share of the face
    (row-scaled diagonal lumping of the face's r-weighted area: positive for every node of a
    quadratic face, the axis node included).

    CalculiX 2.20 on a 2D node (its 3D expansion: 2 degrees of the circumference, or the unit
    thickness) passes half a GAPUNI's spring to the body: the force on the body is k d / 2 for
    that segment (checked statically against a pressure load: 90 k d for the whole circumference),
    while the ground node reports k d. So k = 2 * (the segment's stiffness).

    This wall is exported, not solved (``solver.WALL_REFUSED``): against the face's consistent
    mass the springs chatter at the rod's time step."""
    case = model.case
    if model.dim != 2:
        raise UnsupportedCase("calculix: the rigid wall is exported in 2D only (dim=2)")
    normal = np.asarray(plane_face(model, case.wall.edge).normal, float)[:2]  # outward, towards the wall
    faces = _element_faces(model, cells, model.edge_facets(case.wall.edge), 2)
    area = _lumped_face_area(points, cells, faces, axisymmetric=element == "CAX8")
    struck = np.array(sorted(area))
    slope = case.params["layer_stiffness"] * case.material.E / case.params["layer_thickness"]
    # per ccx segment: 2 degrees of the full circumference (axisymmetric) or the unit thickness
    segment = 1.0 / 180.0 if element == "CAX8" else 1.0
    stiffness = {n: 2.0 * slope * area[n] * segment for n in struck}
    first = points.shape[1] + 1  # ground nodes are numbered after the body's
    ground = np.arange(first, first + struck.size)
    lines = ["*NODE, NSET=GROUND", *(_row([g, *(_number(x) for x in points[:, n])]) for g, n in zip(ground, struck))]
    start = model.rmesh.mesh.nelements + 1
    for j, (n, g) in enumerate(zip(struck, ground)):
        lines += [f"*ELEMENT, TYPE=GAPUNI, ELSET=WALLGAP{j + 1}", f"{start + j}, {n + 1}, {g}",
                  f"*GAP, ELSET=WALLGAP{j + 1}",
                  f"{_number(case.wall.gap)}, {_number(normal[0])}, {_number(normal[1])}, 0., , "
                  f"{_number(stiffness[n])}"]
    lines += ["*BOUNDARY", *(f"{g}, 1, 3" for g in ground)]
    return lines


def _lumped_face_area(points, cells, faces, axisymmetric: bool) -> dict:
    """Node -> its share of the face's area (whole circumference when axisymmetric): on each
    quadratic edge the diagonal of its consistent (r-weighted) mass, scaled to the edge's area."""
    g, w = np.polynomial.legendre.leggauss(4)
    xi, w = (g + 1) / 2, w / 2
    shape = np.array([(1 - xi) * (1 - 2 * xi), 4 * xi * (1 - xi), xi * (2 * xi - 1)])  # end a, middle, end b
    area = {}
    for e, k in faces:
        a, b = (int(cells[e, i]) for i in FACES[2][k - 1])
        m = int(cells[e, 4 + k - 1])
        x = points[:, a][:, None] + np.outer(points[:, b] - points[:, a], xi)
        length = float(np.linalg.norm(points[:, b] - points[:, a]))
        weight = w * length * (2 * np.pi * x[0] if axisymmetric else 1.0)
        diag = (shape**2 * weight).sum(axis=1)
        share = diag / diag.sum() * weight.sum()
        for node, s in zip((a, m, b), share):
            area[node] = area.get(node, 0.0) + float(s)
    return area
