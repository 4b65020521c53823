"""SMFEM contact layer (17)-(19) on the rod impact: 1-D theory, gap, Coulomb friction, and
the failures it must report (penetration through the wall, chattering states)."""

import numpy as np
import pytest

from cases import get_case
from smfem.studies.metrics import moving_average
from smfem.contact import ContactLayer
from smfem.layer_law import NORMAL, SHEAR, SLIP, STICK
from smfem.model import Model
from smfem.options import SolverOptions
from smfem.solver import solve


def rod(**sets):
    case = get_case("rod_impact", sets)
    return case, solve(case, with_fields=True)


def test_nu0_rod_against_one_dimensional_theory():
    # measured: plateau +0.20 %, contact duration +0.66 %, rebound -1.3 % (dt: the reference
    # FEM shows -1.0 % at this dt and -0.6 % at dt / 2), energy conserved to 1e-6
    case, r = rod(nu=0.0)
    th = case.references["rod_theory"]
    assert r.converged, r.message
    a, b = th["t_mid_stress"]
    plateau = (r.t > a + 0.1 * (b - a)) & (r.t < b - 0.1 * (b - a))
    assert abs(r.history["mid_szz"][plateau].mean() / th["stress"] - 1) < 0.02
    first, last = r.info["contact_window"]
    duration = last - first + case.dt
    assert abs(duration / (th["t_contact"][1] - th["t_contact"][0]) - 1) < 0.02
    assert abs(r.history["rod_vz"][-1] / th["rebound_velocity"] - 1) < 0.03
    before, after = r.info["energy_before"], r.info["energy_after"]
    assert before == pytest.approx(0.5 * case.material.rho * np.pi * 0.05**2 * 1.0 * 5.0**2, rel=1e-9)  # J, whole rod
    assert abs(after / before - 1) < 0.01
    # while in contact the face stays on the wall: the layer is compressed, never crossed
    assert 0 < r.info["max_layer_compression"] < 0.01
    assert np.all(r.history["contact_p"] <= 1e-6 * abs(th["stress"]))


def test_gap_delays_first_contact():
    case, r = rod(nu=0.0, gap=1e-4, t_end=1e-4)
    first, _ = r.info["contact_window"]
    assert abs(first - 1e-4 / 5.0) <= 2 * case.dt
    before = r.t < 1e-4 / 5.0 - case.dt
    assert np.allclose(r.history["rod_vz"][before], -5.0, rtol=1e-9)  # free flight until then


def _layer(friction):
    case = get_case("rod_impact", {"friction": friction})
    return ContactLayer(Model(case), 1e-4, 0.03 * case.material.E)


def test_coulomb_block_sticks_below_f_n_and_slides_above():
    """A layer pressed by sigma_n and pulled tangentially: stick while the pull is below
    f |sigma_n|, slip (tangential stress exactly f |sigma_n|, along the pull) above it."""
    layer = _layer(0.4)
    pressed = -1e-3  # normal strain of the layer (compression)
    sigma_n = layer.E * pressed
    for pull_ratio, expect in ((0.5, STICK), (0.99, STICK), (1.01, SLIP), (3.0, SLIP), (-2.0, SLIP)):
        strain = np.zeros(layer.states.kind.shape + (6,))
        strain[..., NORMAL] = pressed
        strain[..., SHEAR[0]] = pull_ratio * 0.4 * abs(sigma_n) / layer.G  # trial tau = ratio f |sigma_n|
        states = layer.states_of(strain)
        assert np.all(states.kind == expect)
        tau = layer.stress(strain, states)[..., SHEAR[0]]
        expected = pull_ratio * 0.4 * abs(sigma_n) if expect == STICK else np.sign(pull_ratio) * 0.4 * abs(sigma_n)
        assert np.allclose(tau, expected, rtol=1e-12)
        assert np.allclose(layer.stress(strain, states)[..., NORMAL], sigma_n, rtol=1e-12)


def test_coulomb_cone_in_both_tangential_directions():
    """Off the axis of symmetry the slip has two components (in the section plane and around
    the circumference): the friction limit is a cone, |tau| <= f |sigma_n|, and a slipping
    point's stress points along the pull."""
    layer = _layer(0.4)
    sigma_n = -layer.E * 1e-3
    pull = np.array([0.6, -0.8])  # unit direction of the tangential pull (g12, g23)
    for ratio, expect in ((0.9, STICK), (1.2, SLIP)):
        strain = np.zeros(layer.states.kind.shape + (6,))
        strain[..., NORMAL] = -1e-3
        strain[..., SHEAR] = ratio * 0.4 * abs(sigma_n) / layer.G * pull
        states = layer.states_of(strain)
        assert np.all(states.kind == expect)
        tau = layer.stress(strain, states)[..., SHEAR]
        assert np.allclose(tau, min(ratio, 1.0) * 0.4 * abs(sigma_n) * pull, rtol=1e-12)


def _face_edge_ur(result):
    x, u = result.mesh.points, result.mesh.point_data["displacement"]
    k = np.argmin(np.hypot(x[:, 0] - 0.05, x[:, 1]) + np.abs(x[:, 2]))
    return u[k, 0]


def test_friction_holds_the_struck_face_against_poisson_expansion():
    # f = 0: the face edge expands freely (measured 14.8 um; nu sigma R / E = 14.4 um);
    # f = 1: the face sticks, and the edge moves only by the layer's own elastic
    # shear (G_l / h = 3.2e13 Pa/m: measured 3.5 um)
    free = _face_edge_ur(rod(friction=0.0, t_end=1e-4)[1])
    held = _face_edge_ur(rod(friction=1.0, t_end=1e-4)[1])
    assert free > 0.9 * 0.3 * 2.02e8 * 0.05 / 2.1e11
    assert abs(held) < 0.3 * free


def test_face_through_the_wall_is_reported():
    case, r = rod(nu=0.0, layer_stiffness=1e-3, v0=50.0, t_end=1e-4)
    assert not r.converged and "through the wall" in r.message and "step" in r.message


def _with_massive_face(monkeypatch, **sets):
    """The run as it would be with the face nodes' mass kept (what mass redistribution cures)."""
    import smfem.contact as contact

    monkeypatch.setattr(contact, "face_free_mass", lambda model, edge, i: model.full_mass(i, i))
    return solve(get_case("rod_impact", sets))


def test_chattering_states_are_settled_by_the_line_search_or_reported(monkeypatch):
    """States that keep coming back are settled, or reported with the step and time, never
    passed over.

    The rod on a tilted wall with friction, sampled at 4 layer points per harmonic around the
    circumference: slip directions at the edge of the contact zone flipped between Newton
    iterates (a 2-cycle at step 344, which damping settled); a point whose slip turns now
    sticks for the next iterate (:func:`smfem.layer_law.stick_where_reversed`), and the steps
    settle without damping (measured once). Over the first 150 steps, held to 2 Newton iterations, the steps that need more go to the
    line-search method (:mod:`smfem.layer_descent`), which settles them (the run names them in
    ``info``, with the same histories to 2.2e-6); with that too held to one iteration, the first such
    step is reported with both reasons.
    """
    import smfem.layer_descent as descent

    case = get_case("rod_impact", {"wall_slope": 0.01, "harmonics": 6, "friction": 0.3, "t_end": 1.5e-4})
    newton = solve(case, SolverOptions(layer_points_per_harmonic=4))
    assert newton.converged and newton.info["line_search_steps"] == []
    two = SolverOptions(layer_points_per_harmonic=4, max_state_iterations=2)
    r = solve(case, two)
    assert r.converged and len(r.info["line_search_steps"]) > 0
    for name in ("contact_p", "rim_uz_0", "rod_vz"):
        scale = np.abs(newton.history[name]).max()
        assert np.abs(r.history[name] - newton.history[name]).max() < 1e-5 * scale, name  # measured 2.2e-6
    monkeypatch.setattr(descent, "MAX_ITERATIONS", 1)
    r = solve(case, two)
    assert not r.converged and "did not settle in 2 iterations" in r.message and "line-search" in r.message
    assert "step" in r.message and "chattering" in r.message


def test_energy_created_by_contact_is_reported(monkeypatch):
    r = _with_massive_face(monkeypatch, nu=0.0, layer_stiffness=0.3)
    assert not r.converged and "created energy" in r.message
    assert r.info["energy_after"] > 1.5 * r.info["energy_before"]


def test_massless_face_conserves_energy_whatever_the_layer_stiffness():
    # measured: energy change < 1e-4 and rebound -1.3 % for E_l = 0.01 E ... 10 E
    for stiffness in (0.03, 1.0, 10.0):
        case, r = rod(nu=0.0, layer_stiffness=stiffness, t_end=4.5e-4)
        assert r.converged, r.message
        assert abs(r.info["energy_after"] / r.info["energy_before"] - 1) < 1e-3


def test_contact_run_writes_the_contract_files(tmp_path):
    from smfem.cli import main

    assert main(["run", "rod_impact", "--set", "t_end=5e-5", "--out", str(tmp_path), "--quiet"]) == 0
    import pandas as pd

    table = pd.read_csv(tmp_path / "history.csv")
    assert list(table.columns) == ["t", "mid_szz", "contact_p", "end_uz", "rod_vz"] and len(table) == 51
    assert np.isfinite(table.values).all()


def transit_filtered(x: np.ndarray, case) -> np.ndarray:
    """Moving average over the time a wave takes to cross the rod's diameter (2 R / c).

    The ringing behind a wave front shorter than that is the discretization's own: it changes
    by 29 % (reference, refine 1 to 2) and 38 % (SMFEM, refine 1 to 4) in L2 between meshes, so
    no two models agree on it; what both resolve is the history seen through this window.
    """
    return moving_average(x, int(round(case.references["comparison_window_s"] / case.dt)))


def test_nu03_displacement_and_velocity_histories_agree_with_the_reference():
    from reference_fem import solve as reference

    # measured: end_uz 0.83 %, rod_vz 0.68 % (max-norm, unfiltered, both at refine 1)
    case = get_case("rod_impact", {"nu": 0.3})
    s, r = solve(case, with_fields=False), reference(case)
    for probe in ("end_uz", "rod_vz"):
        a, b = s.history[probe], r.history[probe]
        assert np.abs(a - b).max() / np.abs(b).max() < 0.05, probe


@pytest.mark.slow
def test_nu03_stress_histories_agree_with_the_reference_through_the_transit_window():
    from reference_fem import solve as reference

    # measured (SMFEM refine 8, 64.9k dof / reference refine 2, 16.4k dof): mid_szz 4.40 %,
    # contact_p 1.95 %, end_uz 0.08 %, rod_vz 0.01 %; SMFEM refine 4: mid_szz 6.6 %
    s = solve(get_case("rod_impact", {"nu": 0.3, "refine": 8}), with_fields=False)
    case = get_case("rod_impact", {"nu": 0.3, "refine": 2})
    r = reference(case)
    for probe, a in s.history.items():
        fa, fb = transit_filtered(a, case), transit_filtered(r.history[probe], case)
        assert np.abs(fa - fb).max() / np.abs(fb).max() < 0.05, probe
