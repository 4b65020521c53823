"""The 9-node Lagrange element (``quad9``, smfem/quad9.py): patch test, orders against exact
elasticity, no locking in thin parts, and dynamics against the reference FEM."""

import numpy as np
import pytest
import scipy.sparse.linalg as sla

from cases import get_case
from cases.analytic import hinged_strip_sine, lame_cylinder
from cases.geometry import PRISM, RING
from helpers import (clamped_plate, with_element, distorted_mesh, dome_with, nearest_node, patch_solution,
                     thick_cylinder_internal_pressure)
from smfem.runs import registry
from smfem.runs.errors import history_errors
from smfem import elements
from smfem.assembly import assemble, weighted_elasticity
from smfem.constitutive import isotropic_D
from smfem.element import strain_rotation
from smfem.model import Model
from smfem.solver import solve
from test_static import strip_case

QUAD9 = elements.QUAD9.name
D = isotropic_D(2.1e11, 0.3)


def stiffness(x, cells, body, p, integrals):
    ops = elements.QUAD9.operators(x[cells], body, 0.3)
    W = np.zeros((len(cells), 2, 2))
    W[:, 0, 0], W[:, 1, 1] = integrals
    return assemble(ops.stiffness(p, weighted_elasticity(D, W)), cells, len(x)).tocsr()


def static(case, element=QUAD9):
    """The model and each mode's full nodal displacements (n_nodes, 3) of a static solve."""
    model = Model(case, element=element)
    return model, [(s.T @ sla.spsolve(s.K.tocsc(), s.Q)).reshape(-1, 3) for s in model.systems]


def orders(errors) -> np.ndarray:
    return -np.diff(np.log(errors)) / np.log(2)


@pytest.mark.parametrize("body", [RING, PRISM])
def test_patch_test_a_linear_field_is_reproduced_on_curved_distorted_elements(body):
    """Boundary nodes follow a linear field with constant strain; the interior follows it to
    round-off on 9-node elements whose interior corner, mid-side and centre nodes are all moved
    (curved edges). Ring (harmonic 0): u_r = a r, u_z = c + d z, on distorted elements too: 3 x 3
    Gauss points integrate the r-weighted terms exactly."""
    x, cells = distorted_mesh(seed=3, order=2)
    K = stiffness(x, cells, body, 0.0, (1.0, 0.0) if body == RING else (1.0, 1.0))
    x1, x2 = x[:, 0], x[:, 1]
    if body == PRISM:
        exact = np.column_stack([2e-3 * x1 + 1e-3 * x2, -1e-3 * x1 + 3e-3 * x2, 1e-3 * x1 - 2e-3 * x2]).ravel()
    else:
        exact = np.column_stack([2e-3 * x1, 1e-3 + 3e-3 * x2, 0 * x1]).ravel()
    # the 4 x 3 elements' node grid; ring harmonic 0, symmetric family: no u_theta
    u = patch_solution(K, exact, (7, 9), 3 if body == PRISM else 2)
    assert np.abs(u - exact).max() < 1e-12 * np.abs(exact).max()


def test_full_integration_leaves_only_the_rigid_modes():
    """Prism, k = 0: four zero-energy modes (u1, u2, u3, rotation about x3), no spurious one
    (2 x 2 reduced integration would add them); k > 0: none."""
    x, cells = distorted_mesh(x1_range=(0.0, 1.0), order=2)
    ev = np.linalg.eigvalsh(stiffness(x, cells, PRISM, 0.0, (1.0, 1.0)).toarray())
    assert np.sum(np.abs(ev) < 1e-12 * np.abs(ev).max()) == 4
    ev = np.linalg.eigvalsh(stiffness(x, cells, PRISM, 3.0, (1.0, 1.0)).toarray())
    assert np.all(ev > 1e-10 * ev.max())


@pytest.mark.parametrize("nu", [0.3, 0.4999])
def test_thick_cylinder_against_lame_converges_at_fourth_order_at_the_nodes(nu):
    """Nodal u_r against Lame, refine 1, 2, 4. Measured (max over the nodes, relative), quad9:
    nu = 0.3: 3.4e-7, 2.1e-8, 1.3e-9 (order 4.0, the nodal superconvergence of a quadratic
    element); nu = 0.4999: 5.4e-4, 3.4e-5, 2.1e-6 (order 4.0: mild volumetric locking on the
    coarsest mesh only); moment4: 6.0e-4, 1.5e-4, 3.8e-5 and 9.2e-4, 2.3e-4, 5.8e-5 (order 2)."""
    errors = {}
    for element in (elements.MOMENT4.name, QUAD9):
        errors[element] = []
        for refine in (1, 2, 4):
            case = thick_cylinder_internal_pressure(1e6, refine=refine, nu=nu)
            model, (u,) = static(case, element)
            exact = lame_cylinder(model.mesh.x[:, 0], 1.0, 2.0, 1e6, 0.0, case.material.E, nu)["u_r"]
            errors[element].append(np.abs(u[:, 0] - exact).max() / np.abs(exact).max())
    assert np.all(orders(errors[QUAD9]) > 3.8) and np.all(np.abs(orders(errors[elements.MOMENT4.name]) - 2) < 0.1)
    assert errors[QUAD9][0] < (1e-6 if nu == 0.3 else 1e-3)


def test_hinged_strip_against_exact_elasticity_converges_at_fourth_order():
    """Plane-strain strip under a sine load: nodal u_z at mid-span. Measured quad9 2.6e-7,
    1.6e-8, 1.0e-9 (order 4.0); moment4 2.7e-4, 6.7e-5, 1.7e-5 (order 2)."""
    errors = []
    for refine in (1, 2, 4):
        model, (u,) = static(strip_case(refine))
        exact = hinged_strip_sine(0.15, model.mesh.x[:, 1], 0.3, 0.1, 1e6, 2.1e11, 0.3)["u_z"]
        errors.append(np.abs(u[:, 1] - exact).max() / np.abs(exact).max())
    assert errors[0] < 1e-6 and np.all(orders(errors) > 3.8)


def test_clamped_plate_does_not_lock():
    """Centre deflection over Kirchhoff's for a/h = 100 and 1000 (4 elements through the
    thickness, element aspect ratio up to 20 x 100): measured 0.9951 and 0.9930 (moment4 0.9915,
    0.9910; the fully integrated bilinear < 0.25 and < 0.01, tests/test_static.py)."""
    for h in (1e-1, 1e-2):
        case = clamped_plate(h)
        model, (u,) = static(case)
        E, nu = case.material.E, case.material.nu
        w0 = 10.0**4 / (64 * E * h**3 / (12 * (1 - nu**2)))
        assert abs(-u[nearest_node(model, 0.0, 0.0), 1] / w0 - 1) < 0.01


def test_thin_dome_does_not_lock_up_to_r_over_h_1000():
    """Apex deflection of the clamped cap at R/h = 100 and 1000 against quad9 on 2 x 320
    elements. Measured at 4 x 20 (and 1 x 20), R/h = 54.3, 100, 200, 543, 1000: quad9 9.1e-4
    (1.8e-3), 8.6e-4 (1.0e-3), 1.8e-3 (1.8e-3), 4.5e-3 (4.5e-3), 6.8e-3 (6.8e-3): the same with
    one element through the thickness as with four, so no locking, and the error grows only
    as the clamped edge's bending layer narrows; moment4 8.6e-3, 1.2e-2, 2.8e-2, 7.3e-2, 1.3e-1
    on the same mesh (it needs 4 x 80 to get as close: 8.4e-4 ... 9.6e-3)."""
    from cases.dome import R

    def apex(h, **mesh):
        model, (u,) = static(dome_with(h, **mesh))
        return u[nearest_node(model, 0.0, R), 1]

    for ratio, tol in ((100, 2e-3), (1000, 1e-2)):
        h = R / ratio
        converged = apex(h, n_thick=2, n_meridian=320)
        four, one = apex(h) / converged - 1, apex(h, n_thick=1) / converged - 1
        assert abs(four) < tol and abs(one) < tol and abs(one - four) < 2e-3


def reference_error(run, reference) -> float:
    """The largest relative max-norm difference of the probe histories (smfem.runs.errors)."""
    return max(history_errors(run.t, run.history[k], reference.t, h)[0] for k, h in reference.history.items())


@pytest.mark.parametrize("name", ["thick_cylinder", "dome"])
def test_dynamics_agree_with_the_reference_better_than_moment4(name):
    """The elastic scene end to end (probes located by the 9-node map, pressure on curved
    3-node edges, lumped 9-node masses) against the reference FEM at the same refine. Measured
    (largest relative max-norm probe error), quad9 against moment4: thick cylinder 1.9e-2 and
    3.9e-2 (at refine 2 both 2.1e-2: the time step's error then dominates); dome 3.5e-3 and
    5.2e-2 (refine 2: 5.3e-4 and 1.4e-2)."""
    case = get_case(name, {"refine": 1})
    reference = registry.solve("reference-2d", case)
    quad = solve(with_element(case, QUAD9), with_fields=False)
    moment = solve(case, with_fields=False)
    assert quad.converged
    assert reference_error(quad, reference) < reference_error(moment, reference)


def test_the_plastic_thick_cylinder_runs_and_agrees_with_the_reference_better_than_moment4():
    """The plastic iterations through the 9 Gauss points (which integrate the stiffness
    exactly, tests/test_element_protocol.py). Measured against the reference at refine 1,
    quad9 (moment4): A_ur 2.3e-3 (9.9e-3), C_ur 1.6e-3 (1.0e-2), peps_A 1.4e-2 (7.3e-2),
    peps_max 3.6e-2 (1.2e-1); the same iterations (292 against 293)."""
    case = get_case("thick_cylinder", {"plastic": True})
    reference = registry.solve("reference-2d", case)
    quad = solve(with_element(case, QUAD9), with_fields=False)
    moment = solve(case, with_fields=False)
    assert quad.converged and reference_error(quad, reference) < 0.5 * reference_error(moment, reference)


def vtk_parametric_coords(order: int) -> np.ndarray:
    """VTK's own parametric coordinates (n_nodes, 3) of its hexahedron's nodes (order 1) or
    its triquadratic hexahedron's (order 2), in [0, 1]."""
    from vtkmodules.vtkCommonDataModel import vtkHexahedron, vtkTriQuadraticHexahedron

    cell = vtkHexahedron() if order == 1 else vtkTriQuadraticHexahedron()
    return np.array(cell.GetParametricCoords()[:3 * cell.GetNumberOfPoints()]).reshape(-1, 3)


@pytest.mark.parametrize("order", [1, 2])
def test_the_field_cells_have_vtks_node_order(order):
    """Each node of a field cell (:data:`smfem.fields.HEX_NODES`: its section node's local
    coordinates and its station along x3) sits at VTK's own parametric coordinates of that node."""
    from smfem.fields import HEX_NODES
    from smfem.quad9 import NODE_I, NODE_J

    section_node, level = HEX_NODES[order]
    ours = np.column_stack([NODE_I[section_node] / 2, NODE_J[section_node] / 2, level / order])
    assert np.array_equal(ours, vtk_parametric_coords(order))


def isoparametric_volume(points: np.ndarray, cells: np.ndarray) -> float:
    """The signed volume of triquadratic hexahedra ``cells`` (n, 27): 3 x 3 x 3 Gauss points on
    VTK's own shape functions."""
    from vtkmodules.vtkCommonDataModel import vtkTriQuadraticHexahedron

    from smfem.quad9 import GAUSS_1D, WEIGHTS_1D

    gauss = np.stack(np.meshgrid(*[0.5 + GAUSS_1D] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    weight = np.einsum("i,j,k->ijk", WEIGHTS_1D, WEIGHTS_1D, WEIGHTS_1D).ravel()
    derivatives = []
    for p in gauss:
        d = [0.0] * 81
        vtkTriQuadraticHexahedron.InterpolationDerivs(list(p), d)
        derivatives.append(np.reshape(d, (3, 27)))
    J = np.einsum("gan,cni->cgai", np.array(derivatives), points[cells])
    return float((np.linalg.det(J) * weight).sum())


def test_a_quad9_run_writes_triquadratic_hexahedra_that_hold_the_curved_body(tmp_path):
    """``smfem run dome --set element=quad9`` writes 27-node cells, in fields.vtu and in the
    frames of fields.pvd, and pyvista reads them. The dome is a spherical shell, curved in the
    section and around the axis; measured against its exact volume at 1 x 5 elements: VTK's own
    cell volumes (``compute_cell_sizes``, which splits a triquadratic cell into 8 linear ones)
    -8.6e-4, the cells' corner hexahedra (what the field had before) -3.4e-3, the isoparametric
    volume of the 27-node cells (VTK's shape functions) -3.6e-7. A ring's cells, bottom face counter-clockwise in (r, z) and top at
    the next angle, are left-handed: their volumes are negative."""
    import pyvista as pv

    from smfem.cli import main
    from smfem.runs.files import read_run

    case = get_case("dome", {"coarsen": 4})  # 1 x 5 elements
    sets = ["element=quad9", "coarsen=4", f"t_end={2 * case.dt}"]
    assert main(["run", "dome", *(a for s in sets for a in ("--set", s)), "--every", "1", "--out", str(tmp_path),
                 "--quiet", "--estimate", "off"]) == 0
    run, _ = read_run(tmp_path)
    n_cells = 72 * Model(case, element=QUAD9).mesh.n_elements
    for mesh in [run.mesh] + [frame for _, frame in run.frames]:
        assert [(block.type, block.data.shape) for block in mesh.cells] == [("hexahedron27", (n_cells, 27))]
    assert len(run.frames) == 3
    (inner, outer), (_, opening) = case.section.s.span, case.section.t.span
    exact = 2 * np.pi / 3 * (outer ** 3 - inner ** 3) * (1 - np.cos(opening))
    field = pv.read(tmp_path / "fields.vtu")
    assert field.n_cells == n_cells and set(field.celltypes) == {pv.CellType.TRIQUADRATIC_HEXAHEDRON}
    cells = run.mesh.cells[0].data
    corners = pv.UnstructuredGrid({pv.CellType.HEXAHEDRON: cells[:, :8]}, run.mesh.points)
    error_vtk = -field.compute_cell_sizes()["Volume"].sum() / exact - 1
    error_corners = -corners.compute_cell_sizes()["Volume"].sum() / exact - 1
    error_isoparametric = -isoparametric_volume(run.mesh.points, cells) / exact - 1
    assert abs(error_vtk) < 0.3 * abs(error_corners) and abs(error_isoparametric) < 1e-6


@pytest.mark.parametrize("name", ["thick_cylinder", "strip"])
def test_the_field_cells_stations_carry_the_synthesized_displacement(name):
    """A 27-node cell's nodes lie at its bottom, middle and top stations along x3 (a ring's last
    sector closing on the first station), and the field's displacement at the middle station's
    nodes is the synthesis there: the probes' (:class:`smfem.probes.ProbeSet`) at the node's
    position, for random amplitudes of every harmonic. Each node's station is VTK's (its third
    parametric coordinate), not the field's own table."""
    from cases.geometry import Probe
    from smfem.fields import field_mesh
    from smfem.probes import ProbeSet

    case = with_element(strip_case(1) if name == "strip" else get_case(name), QUAD9)
    model = Model(case, element=QUAD9)
    rng = np.random.default_rng(1)
    u_modes = [rng.standard_normal(s.T.shape[1]) for s in model.systems]
    n_x3, ne = 4, model.mesh.n_elements
    field = field_mesh(model, u_modes, n_x3=n_x3)
    ring = model.body == RING
    period = 2 * np.pi if ring else model.length
    zeta = vtk_parametric_coords(2)[:, 2]  # 0, 1/2, 1: bottom, middle, top
    chosen = np.array([0, n_x3 * ne - 1])  # the first sector's (slice's) first cell, the last one's last
    nodes = field.cells[0].data[chosen]  # (2, 27)
    x = field.points[nodes]
    if ring:  # (r, z), theta
        section = np.stack([np.hypot(x[..., 0], x[..., 1]), x[..., 2]], axis=-1)
        x3 = np.arctan2(x[..., 1], x[..., 0])
    else:  # (x1, x2), x3
        section, x3 = x[..., 1:], x[..., 0]
    expected = (chosen[:, None] // ne + zeta) * period / n_x3
    off = x3 - expected
    assert np.abs((off + period / 2) % period - period / 2 if ring else off).max() < 1e-12
    middle = zeta == 0.5
    probes = [Probe(f"u{c}", "point", "u", (c,), (*p, at)) for p, at in
              zip(section[:, middle].reshape(-1, 2), expected[:, middle].ravel()) for c in (1, 2, 3)]
    u1, u2, u3 = ProbeSet(model, probes).evaluate(np.concatenate(u_modes), None).reshape(-1, 3).T
    c, s = np.cos(expected[:, middle].ravel()), np.sin(expected[:, middle].ravel())
    synthesized = np.column_stack([u1 * c - u3 * s, u1 * s + u3 * c, u2] if ring else [u3, u1, u2])
    written = field.point_data["displacement"][nodes[:, middle]].reshape(-1, 3)
    assert np.abs(written - synthesized).max() < 1e-10 * np.abs(synthesized).max()


def test_the_strain_on_the_axis_is_its_limit():
    """A 9-node element evaluates its strain at the point itself (the rod's mid_szz probe lies on
    the axis): there ``u_r / r`` and the other hoop terms take their limits (smfem/element.py).
    Harmonic 0, u_r = a r, u_z = c z: e_rr = e_thth = a, e_zz = c; harmonic 1, the axis's
    lateral translation (u_r = U, u_theta = -U): no strain. On distorted 9-node elements."""
    x, cells = distorted_mesh(x1_range=(0.0, 1.0), seed=1, order=2)
    first = np.flatnonzero(np.isclose(x[cells[:, :4], 0].min(axis=1), 0.0))  # the elements on the axis
    ops = elements.QUAD9.operators(x[cells[first]], RING, 0.3)
    a, c, U = 2e-3, -1e-3, 1e-4
    stretch = np.column_stack([a * x[:, 0], c * x[:, 1], 0 * x[:, 0]])[cells[first]].reshape(len(first), -1)
    shift = np.tile([U, 0.0, -U], (len(first), 9))
    for eta in (-0.5, 0.1, 0.5):
        strain = np.einsum("erk,ek->er", ops.strain(0.0, -0.5, eta), stretch)
        global_ = np.einsum("ers,es->er", np.linalg.inv(strain_rotation(ops.rotation)), strain)
        assert np.allclose(global_[:, :4], [a, c, a, 0.0], rtol=0, atol=1e-12)
        assert np.abs(np.einsum("erk,ek->er", ops.strain(1.0, -0.5, eta), shift)).max() < 1e-15


def test_the_contact_layer_on_three_node_face_segments_loads_the_face_consistently():
    """A uniform closure d of the layer (stick) gives the face the nodal forces of the uniform
    pressure E_l d / h integrated with the face's own quadratic functions (1:4:1 per segment,
    times r): the 6-node layer elements of smfem/contact.py. Two straight 2-node facets per
    segment would give 1:2:1 (measured 0.75 and 1.5 times these forces); the face's lumped
    masses, moved one node row in, keep the body's total."""
    from smfem.contact import ContactLayer, face_free_mass
    from smfem.layer_law import STICK, LayerStates
    from smfem.loads import edge_pressure_vector

    case = get_case("rod_impact", {"element": QUAD9})
    model = Model(case)
    layer = ContactLayer(model, 1e-4, case.material.E)
    assert layer.B.shape[1] == 3 * model.mesh.shape[0]  # 3 Gauss points per face segment
    d = 1e-7
    u = np.where(layer.F % 3 == 1, -d, 0.0)  # the face moved d towards the wall
    shape = layer.states.kind.shape
    force = -layer.face_matrix(LayerStates(np.full(shape, STICK), np.zeros(shape + (2,)), np.zeros(shape))) @ u
    expected = 2 * np.pi * layer.E * d / layer.h * edge_pressure_vector(model.mesh, "face", case.body)[layer.F]
    assert np.abs(force - expected).max() < 1e-12 * np.abs(expected).max()
    mass = face_free_mass(model, "face")
    assert np.all(mass.reshape(-1, 3)[model.mesh.edge_nodes("face")] == 0)
    assert mass.sum() == pytest.approx(model.full_mass(0, 0).sum(), rel=1e-14)


def test_rod_impact_on_the_nine_node_body_agrees_with_moment4_on_the_finer_mesh():
    """The first 100 us of the rod impact, quad9 at refine 1 against moment4 at refine 2 (the
    same 4221 unknowns), through the 2R/c window. Measured: contact_p 0.82 %, end_uz 2.3 %,
    rod_vz 0.012 % (moment4 at refine 1: 3.0 %, 8.3 %, 0.17 %); the whole face closed from the
    second step on, at most 2 state iterations per step, energy kept to 4e-13. With each face
    segment split into two 2-node facets the axis point stays open and end_uz is 8 times off."""
    case = get_case("rod_impact", {"element": QUAD9, "t_end": 1e-4})
    quad = solve(case, with_fields=False)
    fine = solve(get_case("rod_impact", {"refine": 2, "t_end": 1e-4}), with_fields=False)
    assert quad.converged, quad.message
    window = case.references["comparison_window_s"]
    error = {p: history_errors(quad.t, quad.history[p], fine.t, fine.history[p], window)[0]
             for p in ("contact_p", "end_uz", "rod_vz")}
    assert error["contact_p"] < 0.02 and error["end_uz"] < 0.05 and error["rod_vz"] < 1e-3, error
    assert np.all(np.array(quad.info["closed_fraction"][2:]) == 1.0) and quad.info["iterations_max"] <= 2
    assert abs(quad.info["energy_after"] / quad.info["energy_before"] - 1) < 1e-9


def test_friction_holds_the_nine_node_face():
    """f = 1: at 50 us the struck face's rim stays within 0.21 um (measured) of where it
    started, where without friction Poisson's expansion moves it 15.8 um (nu sigma R / E =
    14.4 um); each layer point holds its own shear (moment4's layer holds the element means:
    3.5 um, tests/test_contact.py)."""
    run = solve(get_case("rod_impact", {"element": QUAD9, "friction": 1.0, "t_end": 5e-5}))
    x, u = run.mesh.points, run.mesh.point_data["displacement"]
    rim = np.argmin(np.hypot(x[:, 0] - 0.05, x[:, 1]) + np.abs(x[:, 2]))
    assert run.converged and abs(u[rim, 0]) < 0.1 * 0.3 * 2.02e8 * 0.05 / 2.1e11


def test_the_element_is_a_scene_parameter(tmp_path, capsys):
    """``--set element=quad9`` runs the quadratic element (more unknowns on the same mesh, its
    name in summary.json's params); a name that is not one of the scene's choices exits 2."""
    import json

    from smfem.cli import main

    for element in ("moment4", "quad9"):
        assert main(["run", "dome", "--set", f"element={element}", "--set", "t_end=2e-5", "--out",
                     str(tmp_path / element), "--quiet", "--no-fields", "--estimate", "off"]) == 0
    m4, q9 = (json.loads((tmp_path / e / "summary.json").read_text()) for e in ("moment4", "quad9"))
    assert q9["params"]["element"] == "quad9" and q9["n_dof"] > 2 * m4["n_dof"]
    capsys.readouterr()
    assert main(["run", "dome", "--set", "element=quad8", "--out", str(tmp_path / "bad"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "element='quad8' is out of range: element must be one of moment4, quad9" in err, err


def test_the_lumped_masses_are_the_nodal_rules_none_negative_the_axis_nodes_none():
    """The element's nodal rule (smfem/quad9.py): on a parallelogram with r linear across it
    the masses are the row sums ``int N_i dV`` (a prism's 1:4:16 per 36); on distorted elements
    none is negative, a node on the axis has none, exactly, and every element keeps its
    volume. The row sums themselves gave the axis nodes round-off of either sign and an
    element widening away from the axis a negative mass (the gmsh rod: 226 masses down to
    -8e-7 kg)."""
    x, cells = distorted_mesh(x1_range=(0.0, 1.0), seed=1, order=2)
    N = None
    for body in (RING, PRISM):
        ops = elements.QUAD9.operators(x[cells], body, 0.3)
        share = ops.node_volume
        assert share.min() >= 0
        assert np.allclose(share.sum(axis=1), ops.sample_weights.sum(axis=1), rtol=1e-13)
        on_axis = x[cells, 0] == 0.0
        assert on_axis.any() and (share[on_axis] == 0).all() == (body == RING)
        assert share[~on_axis].min() > 0
    from smfem.quad9 import GAUSS_ETA, GAUSS_XI, shape_functions
    N = shape_functions(GAUSS_XI, GAUSS_ETA)[0]
    for body, origin in ((PRISM, 0.0), (RING, 0.0), (RING, 0.7)):  # a parallelogram; on the axis; off it
        corners = np.array([[0.0, 0.0], [0.5, 0.2], [0.5, 1.2], [0.0, 1.0]]) + [origin, 0.0]
        nodes = np.concatenate([corners, 0.5 * (corners + np.roll(corners, -1, axis=0)),
                                corners.mean(0, keepdims=True)])
        ops = elements.QUAD9.operators(nodes[None], body, 0.3)
        assert np.allclose(ops.node_volume, ops.sample_weights @ N, rtol=1e-12, atol=1e-15)
        if body == PRISM:
            assert np.allclose(ops.node_volume[0] * 36 / 0.5, [1, 1, 1, 1, 4, 4, 4, 4, 16], rtol=1e-13)


def test_the_gmsh_rods_masses_are_none_negative_and_its_impact_keeps_its_energy_at_small_steps():
    """The cause of exit 3 at dt 5e-7 on examples/rod_impact_unstructured.toml with quad9: its
    axis nodes had negative lumped masses (an unstable mode whose growth per step Newmark's
    average acceleration raises as dt falls: at 5e-7 s, mid_szz grew 1.17 times a step and the
    run ended at step 724 with the layer crushed). No mass is negative now (the axis nodes'
    are zero), and the first
    0.2 ms at dt 2.5e-7 keep the energy (measured +1e-7) with the axis stress bounded by
    the impact's rho c v0."""
    case = get_case("examples/rod_impact_unstructured.toml", {"element": QUAD9, "dt": 2.5e-7, "t_end": 2e-4})
    model = Model(case)
    mass = model.full_mass(0, 0).reshape(-1, 3)[:, :2]
    on_axis = model.mesh.x[:, 0] <= 1e-6
    assert mass.min() >= 0 and (mass[on_axis] == 0).all() and mass[~on_axis].min() > 0
    run = solve(case, with_fields=False)
    assert run.converged, run.message
    assert abs(run.info["energy_after"] / run.info["energy_before"] - 1) < 1e-5
    E, rho, v0 = case.material.E, case.material.rho, case.params["v0"]
    assert np.abs(run.history["mid_szz"]).max() < 2 * np.sqrt(E * rho) * v0
