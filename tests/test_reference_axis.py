"""The 3D reference on a mesh section that reaches the axis (reference_fem/ties.py): the swept
hexahedra there are degenerate, their nodes at one axis point tied into one unknown. A uniform
strain is reproduced exactly (the patch test), the manufactured motion through the axis
(cases/verification_axis.py) converges at the quadratic element's order, and SMFEM agrees."""

import numpy as np
import pytest
import scipy.sparse.linalg as sla

from cases import verification_axis as va
from cases.geometry import RING
from cases.msh_section import read_msh
from reference_fem import ties
from reference_fem.forms import SQRT2
from reference_fem.model import Model
from smfem.runs.registry import solve


@pytest.fixture(scope="module")
def section(tmp_path_factory):
    return read_msh(va.write(tmp_path_factory.mktemp("axis") / "square.msh"), RING)


def scene(section, **params):
    return va.build(section, dict({"dim": 3, "time": "quadratic", "dt": 0.05, "t_end": 0.25, "theta_elements": 8},
                                  **params))


def test_the_axis_nodes_are_one_unknown_and_nothing_else_is_tied(section):
    """Every node at one point of the axis is one unknown; no two unknowns share a point; the
    axis facets (lines) are on no named edge."""
    model = Model(scene(section))
    mesh = model.rmesh.mesh
    x = model.nodes_x
    r = np.hypot(x[0], x[1])
    key = np.round(x / 1e-9).astype(np.int64)
    assert len(np.unique(key, axis=1).T) == x.shape[1]  # one unknown per point
    on_axis = r < 1e-12
    assert on_axis.sum() == len(np.unique(np.round(x[2, on_axis], 9)))  # one per height
    assert mesh.doflocs.shape[1] > x.shape[1]  # the mesh keeps the axis nodes apart, one per angle
    assert model.basis.N == 3 * x.shape[1]
    outer = model.edge_facets("outer")
    corners = mesh.p[:, mesh.facets[:, outer]]
    assert np.all(np.hypot(corners[0], corners[1]).max(axis=0) > 1e-9)  # no axis line among them


@pytest.mark.parametrize("refine, theta_elements", [(1, 8), (2, 4)])
def test_the_patch_test_a_uniform_strain_is_reproduced_through_the_axis(section, refine, theta_elements):
    """u = A x + b on the body's boundary (its outer surface; the axis is inside): the solve
    gives it at every node, the axis's included, and the uniform stress at every quadrature
    point (the degenerate elements' points among them). The section split 1 x 1 with 8
    elements round the axis, and 2 x 2 (more axis nodes inside) with 4 round (with 8 round: 14k
    unknowns, 7 s of the sparse solve)."""
    model = Model(scene(section, refine=refine, theta_elements=theta_elements))
    A = np.array([[1.0, 0.3, -0.2], [0.5, -0.7, 0.1], [0.2, 0.4, 0.9]]) * 1e-3
    b = np.array([1e-4, -2e-4, 3e-4])
    exact = (A @ model.nodes_x + b[:, None]).T.ravel()
    x = model.nodes_x
    r, z = np.hypot(x[0], x[1]), x[2]
    boundary = np.isclose(r, 1.0) | np.isclose(z, 0.0) | np.isclose(z, 1.0)
    assert (~boundary & (r < 1e-12)).sum() >= 2 * refine - 1  # the axis nodes inside are free
    known = np.repeat(boundary, 3)
    K = model.stiffness().tocsr()
    u = exact.copy()
    u[~known] = sla.spsolve(K[~known][:, ~known].tocsc(), -(K[~known][:, known] @ exact[known]))
    assert np.abs(u - exact).max() < 1e-12 * np.abs(exact).max() * 1e3
    strain = model.B @ u  # Mandel components at every quadrature point
    eps = 0.5 * (A + A.T)
    expected = np.array([eps[0, 0], eps[1, 1], eps[2, 2], SQRT2 * eps[1, 2], SQRT2 * eps[0, 2], SQRT2 * eps[0, 1]])
    got = strain.reshape(-1, 6)
    assert np.abs(got - expected).max() < 1e-9 * np.abs(expected).max()


def test_the_manufactured_motion_through_the_axis_converges_at_third_order(section):
    """The 3D reference's L2 error at the end of five steps of t^2 (exact in time: the mesh's
    error alone), the section split k x k and 4 k elements round: it falls at the quadratic
    element's order, 3 (measured 2.97; 3.26 and 3.02 with 6 k and 8 k round), and the
    displacement on the axis is the exact one."""
    errors, runs = [], []
    for refine in (1, 2):
        run = solve("reference-3d", scene(section, refine=refine, theta_elements=4 * refine))
        assert run.converged, run.message
        errors.append(run.info["error_l2"])
        runs.append(run)
    order = np.log2(errors[0] / errors[1])
    assert abs(order - 3) < 0.4, errors
    exact = va.exact(scene(section), runs[-1].t)
    for name in ("axis_uz", "axis_ux"):
        assert abs(runs[-1].history[name][-1] / exact[name][-1] - 1) < 1e-3, name


@pytest.mark.parametrize("element, theory", [("moment4", 2), ("quad9", 3)])
def test_smfem_converges_on_the_motion_through_the_axis(section, element, theory):
    """SMFEM's L2 error on the same motion (harmonics 0-2, four kept), the section split 2, 4
    and 8 times: the moment scheme at its order 2 (measured 1.88, 1.97), the 9-node element at
    least at its 3 (measured 3.60, 3.37: its error is still falling faster)."""
    errors = []
    for refine in (2, 4, 8):
        run = solve("smfem", scene(section, dim=2, refine=refine, element=element))
        assert run.converged, run.message
        errors.append(run.info["error_l2"])
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert orders[-1] > theory - 0.15 and (element == "quad9" or abs(orders[-1] - theory) < 0.15), errors


def test_the_harmonic_model_takes_every_harmonic_of_a_section_through_the_axis():
    """reference_fem/harmonic.py on the gmsh puck (examples/puck_strike.toml): harmonic 1's
    axis nodes move as one (u_theta = -u_r there: the lateral translation, which costs no
    energy), harmonics >= 2's not at all. Its modal histories (exact in time) against SMFEM's at
    a quarter of the scene's step, on the same section elements: measured patch_uz 0.10 %,
    far_uz 1.3 %, top_uz 1.2 %, bottom_ux 1.9 % (consistent against lumped mass); with
    u_theta = +u_r on the axis instead, bottom_ux is 450 times off."""
    from pathlib import Path

    from cases import get_case
    from reference_fem.harmonic import HarmonicModel
    from reference_fem.modal import solve as modal

    scene = Path(__file__).resolve().parents[1] / "examples" / "puck_strike.toml"
    case = get_case(scene, {"harmonics": 8})
    model = HarmonicModel(case)
    first = next(h for h in model.systems if h.l == 1)
    T = model._reduction(1)
    n = model.tie.shape[1]
    shift = np.zeros(3 * n)
    shift[:n], shift[2 * n:] = 1.0, -1.0  # U = 1, V = -1 everywhere: the body moved sideways
    reduced = sla.lsqr(T, shift, atol=1e-14, btol=1e-14)[0]
    assert np.abs(T @ reduced - shift).max() < 1e-10  # the translation is one of its motions
    assert np.abs(first.K @ reduced).max() < 1e-9 * np.abs(first.K).max()  # and costs nothing
    exact = modal(case)
    run = solve("smfem", get_case(scene, {"harmonics": 8, "element": "quad9", "dt": case.dt / 4}))
    for name, bound in (("patch_uz", 0.005), ("far_uz", 0.03), ("top_uz", 0.03), ("bottom_ux", 0.03)):
        ours = np.interp(exact.t, run.t, run.history[name])
        assert np.abs(ours - exact.history[name]).max() < bound * np.abs(exact.history[name]).max(), name


def test_a_face_through_the_axis_has_a_normal_at_every_node(section):
    """The outer face (the bottom and top discs through the axis, the cylinder): each node's
    normal from the facets round it (reference_fem/face.py; a degenerate facet's collapsed
    corner has no Jacobian, so its normal is taken a hair inside), outward, and its area."""
    from reference_fem.face import AXIS_INSET, face_of

    model = Model(scene(section))
    face = face_of(model, "outer")
    x = model.nodes_x[:, face.nodes]
    r = np.hypot(x[0], x[1])
    # on the discs the tangents a hair from a collapsed corner are O(AXIS_INSET) differences of
    # O(1) coordinates, so their direction carries eps / AXIS_INSET of rounding (measured 7 times
    # that on the top disc, z = 1; the error grows about as 1 / AXIS_INSET from 1e-4 to 1e-7)
    rounding = 30 * np.finfo(float).eps / AXIS_INSET
    for plane, z in ((-1.0, 0.0), (1.0, 1.0)):
        on = np.isclose(x[2], z) & (r < 0.99)
        assert (r[on] < 1e-12).any() and np.abs(face.normals[on] - [0.0, 0.0, plane]).max() < rounding
    side = np.isclose(r, 1.0) & (x[2] > 0.01) & (x[2] < 0.99)
    assert np.abs(face.normals[side][:, :2] - (x[:2, side] / r[side]).T).max() < 1e-9
    assert face.area == pytest.approx(4 * np.pi, rel=2e-3)  # 8 quadratic arcs round


def test_the_mirror_half_of_a_body_through_the_axis_gives_the_wholes_histories():
    """The puck (examples/puck_strike.toml: a gmsh disc through its axis, struck on a patch
    symmetric about theta = 0) meshed whole and as its half 0 <= theta <= pi (u_theta = 0 on the
    mirror planes, the axis's nodes on both): the same histories (measured to 6e-13), half the
    unknowns."""
    from pathlib import Path

    from cases import get_case

    scene = Path(__file__).resolve().parents[1] / "examples" / "puck_strike.toml"
    sets = {"dim": 3, "theta_elements": 4, "t_end": 2.5e-6}
    whole = solve("reference-3d", get_case(scene, sets))
    half = solve("reference-3d", get_case(scene, {**sets, "mirror": True}))
    assert half.n_dof < 0.6 * whole.n_dof
    for name, values in whole.history.items():
        assert np.abs(half.history[name] - values).max() <= 1e-9 * np.abs(values).max(), name
