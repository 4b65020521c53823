"""Reference FEM, contact with a rigid wall: Lagrange multipliers and an active set.

The rod of ``rod_impact`` against 1-D rod theory (nu = 0), the gap, non-penetration, the
face and body probes, Coulomb friction on a pulled block, chatter reporting, 2D against 3D.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.sparse as sp

from cases import UnsupportedCase, get_case
from reference_fem import Model, contact, solve, static
from reference_fem.contact import OPEN, SLIP, STICK, ContactNotSettled, WallContact, WallRows
from reference_fem.face import plane_face
from reference_fem.friction_block import pulled_block
from reference_fem.mass import consistent_mass
from reference_fem.newmark import march
from reference_fem.probes import Probes
from reference_fem.solver import _system
from reference_fem.newmark import newmark_constants

#: round-off level of a wall penetration (m), for a rod 1 m long
PENETRATION = 1e-12


def rod(**overrides):
    return get_case("rod_impact", overrides)


def plateau_mean(result, name, window) -> float:
    """Mean of probe ``name`` over the middle 80 % of the time ``window`` (s)."""
    a, b = window
    inside = (result.t > a + 0.1 * (b - a)) & (result.t < b - 0.1 * (b - a))
    return float(result.history[name][inside].mean())


def contact_times(result, stress) -> np.ndarray:
    """Times (s) at which the wall pushes (mean face stress beyond 0.1 % of ``stress``)."""
    return result.t[result.history["contact_p"] < -1e-3 * abs(stress)]


@pytest.fixture(scope="module")
def rod_nu0():
    return solve(rod(nu=0.0))


@pytest.fixture(scope="module")
def rod_nu03():
    return solve(rod())


def test_rod_against_1d_theory(rod_nu0):
    """nu = 0 (1-D theory exact): duration, plateau stress, rebound, energy.

    Measured at refine 1 (2D, 4221 dof): duration +0.4 %, mid-length plateau -0.06 %, wall
    stress plateau +0.001 %, rebound velocity -1.0 %, energy +0.005 %.
    """
    res, theory = rod_nu0, rod(nu=0.0).references["rod_theory"]
    assert res.converged
    on = contact_times(res, theory["stress"])
    duration = on[-1] - theory["t_contact"][0]
    assert duration == pytest.approx(theory["t_contact"][1] - theory["t_contact"][0], rel=0.02)
    assert plateau_mean(res, "mid_szz", theory["t_mid_stress"]) == pytest.approx(theory["stress"], rel=0.02)
    assert plateau_mean(res, "contact_p", theory["t_contact"]) == pytest.approx(theory["stress"], rel=0.02)
    assert res.history["rod_vz"][0] == pytest.approx(-theory["rebound_velocity"], rel=1e-12)
    assert res.history["rod_vz"][-1] == pytest.approx(theory["rebound_velocity"], rel=0.03)
    # kinetic + strain energy of the whole rod: m v0^2 / 2 before, kept by the impact
    mass = 7.8e3 * np.pi * 0.05**2 * 1.0
    assert res.info["energy_before"] == pytest.approx(0.5 * mass * 5.0**2, rel=1e-9)
    assert res.info["energy_after"] == pytest.approx(res.info["energy_before"], rel=1e-3)
    assert res.info["contact_window"] == pytest.approx([on[0], on[-1]])


def test_no_penetration_at_any_step(rod_nu0, rod_nu03):
    for res in (rod_nu0, rod_nu03):
        assert res.info["max_penetration"] <= PENETRATION


def test_gap_delays_contact_by_gap_over_v0(rod_nu0):
    """A gap of 20 v0 dt shifts the whole history by exactly 20 steps; another lands within a step."""
    base = rod(nu=0.0)
    dt, v0 = base.dt, base.params["v0"]
    steps = 20
    res = solve(rod(nu=0.0, gap=steps * v0 * dt, t_end=base.t_end / 2))
    n = len(res.t) - steps
    assert res.info["max_penetration"] <= PENETRATION
    for name in ("mid_szz", "contact_p", "rod_vz"):
        scale = np.abs(rod_nu0.history[name][:n]).max()
        np.testing.assert_allclose(res.history[name][steps:], rod_nu0.history[name][:n], atol=1e-6 * scale)
    np.testing.assert_allclose(res.history["end_uz"][steps:] + steps * v0 * dt,
                               rod_nu0.history["end_uz"][:n], atol=1e-9)
    gap = 12.3 * v0 * dt
    res = solve(rod(nu=0.0, gap=gap, t_end=40 * dt))
    first = contact_times(res, base.references["rod_theory"]["stress"])[0]
    assert 0 < first - gap / v0 <= dt
    assert res.history["end_uz"][res.t < gap / v0] == pytest.approx(-v0 * res.t[res.t < gap / v0])
    assert res.info["max_penetration"] <= PENETRATION


def test_active_set_settles_in_few_iterations(rod_nu0, rod_nu03):
    """One solve per step while the contact set stays; a few when it changes."""
    for res in (rod_nu0, rod_nu03):
        its = np.array(res.iterations)
        assert its.max() <= 4 and np.median(its) == 1
        assert res.info["factorizations"] == 1


def test_contact_probe_is_the_wall_reaction():
    """contact_p (nodal reactions K u + M a of the face) = -(sum of multipliers) / face area."""
    case = rod(t_end=30e-6)
    model = Model(case)
    system = _system(model, newmark_constants(case.dt).a0)
    probes = Probes(model)
    k = probes.names.index("contact_p")
    area = plane_face(model, "face").area
    full = [np.zeros(model.basis.N) for _ in range(3)]
    for _, _, u, v, a, _ in march(system, model.Q[model.free], np.zeros(model.free.size),
                                  model.initial_velocity()[model.free], case.dt, case.n_steps):
        for f, x in zip(full, (u, v, a)):
            f[model.free] = x
        wall_force = system.state.p[: system.rows.n_c].sum()
        assert probes.values(full[0], system, full[1], full[2])[k] == pytest.approx(-wall_force / area, rel=1e-8)
    assert wall_force > 0


def test_redistributed_mass_keeps_mass_and_centre_and_frees_the_face():
    """The layer at the wall: same total mass and centre of mass, no mass on the face's nodes."""
    model = Model(rod(dim=2))
    consistent = consistent_mass(model.basis, model.case.material.rho, axisymmetric=True)
    dim, z = model.dim, model.basis.doflocs[1]
    axial = (np.arange(model.basis.N) % dim == 1).astype(float)
    for M in (model.M, consistent):
        assert axial @ (M @ axial) == pytest.approx(7.8e3 * 0.05**2 / 2, rel=1e-12)
        assert (z * axial) @ (M @ axial) == pytest.approx(7.8e3 * 0.05**2 / 2 * 0.5, rel=1e-12)
    face_dofs = (plane_face(model, "face").nodes[:, None] * dim + np.arange(dim)).ravel()
    assert abs(model.M[face_dofs]).max() == 0.0
    assert abs(consistent[face_dofs]).max() > 0.0


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("pull", [0.5, 0.9, 1.1, 1.5])
def test_block_sticks_below_and_slides_above_the_friction_limit(pull, dim):
    """A block pressed with N and pulled with P = pull f N: bound below f N, sliding above it.

    Sliding: the wall's friction is f times its normal force and the block accelerates at
    (P - f N) / m (measured within 0.1 %). Sticking: friction balances the pull and the block
    stays at rest (edge nodes may slip a little: partial slip).
    """
    f = 0.3
    counts = (4, 4, 2) if dim == 2 else (2, 2, 1)
    run = pulled_block(f, pull, dim=dim, counts=counts)
    held = run.t > run.t[-1] - 5 * (run.t[1] - run.t[0])
    accel = np.polyfit(run.t[held], run.velocity[held], 1)[0]
    assert run.normal[-1] == pytest.approx(run.N, rel=5e-3)
    if pull < 1:
        assert run.friction[-1] == pytest.approx(-run.P, rel=5e-3)
        assert np.abs(run.velocity).max() < 1e-3 * (run.P / run.mass) * run.t[-1]
        assert np.any(run.states[-1] == STICK)
    else:
        closed = run.states[-1] != OPEN
        assert np.all(run.states[-1][closed] == SLIP)
        assert run.friction[-1] == pytest.approx(-f * run.normal[-1], rel=1e-6)
        assert accel == pytest.approx((run.P - f * run.N) / run.mass, rel=2e-3)


def test_partial_slip_below_the_limit_still_holds_the_block():
    """3D, a finer block at 0.9 f N: some edge nodes slip (the slip zone), the block holds."""
    run = pulled_block(0.3, 0.9, dim=3, counts=(4, 4, 2))
    assert np.any(run.states[-1] == SLIP) and np.any(run.states[-1] == STICK)
    assert run.friction[-1] == pytest.approx(-run.P, rel=5e-3)
    assert np.abs(run.velocity).max() < 1e-3 * (run.P / run.mass) * run.t[-1]


def test_friction_on_the_rod_face():
    """The rod with friction: same 1-D plateau, less radial bulging, energy lost only to slip."""
    res = solve(rod(friction=0.3))
    assert res.converged and res.info["max_penetration"] <= PENETRATION
    assert res.info["energy_after"] < res.info["energy_before"]
    theory = rod().references["rod_theory"]
    assert plateau_mean(res, "contact_p", theory["t_contact"]) == pytest.approx(theory["stress"], rel=0.02)


class _Identity:
    """A stand-in factorization of the identity: then S = H H^T."""

    @staticmethod
    def solve(h):
        return np.array(h, float)


def test_a_cycling_active_set_is_detected():
    """Primal-dual active set on a contact matrix that is no M-matrix can cycle: it must be caught."""
    L = np.array([[1.753, 0.0, 0.0], [-0.777, 0.803, 0.0], [1.392, -0.348, 0.061]])
    problem = WallContact(_Identity(), WallRows(sp.csr_matrix(L), np.zeros(3), np.arange(3), 0.0, 1e-12))
    with pytest.raises(ContactNotSettled, match="chatters"):
        problem.solve(np.array([-0.145, 2.183, -1.641]), np.zeros(3), problem.initial())


def test_unsettled_contact_stops_the_run_with_step_and_time(monkeypatch):
    monkeypatch.setattr(contact, "MAX_ITERATIONS", 1)
    res = solve(rod(t_end=20e-6))
    assert not res.converged
    assert "step 1 (t = 1e-06 s)" in res.message and "not settled" in res.message
    assert len(res.t) == 1 and res.iterations == []


def test_unsupported_contact_variants():
    with pytest.raises(UnsupportedCase, match="static"):
        static(rod())
    with pytest.raises(UnsupportedCase, match="plasticity"):
        solve(rod(plastic=True, t_end=1e-5))


def test_cli_runs_rod_impact_with_the_reference(tmp_path):
    from smfem.cli import main

    out = tmp_path / "rod"
    assert main(["run", "rod_impact", "--solver", "reference", "--set", "t_end=5e-5", "--out", str(out), "--quiet"]) == 0
    header = (out / "history.csv").read_text().splitlines()[0]
    assert header == "t,mid_szz,contact_p,end_uz,rod_vz"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] and summary["info"]["max_penetration"] <= PENETRATION


@pytest.mark.slow
@pytest.mark.parametrize("nu", [0.0, 0.3])
def test_rod_3d_against_2d(nu, rod_nu0, rod_nu03):
    """Full 3D rod (O-grid, 2 + 2 radial x 50 quadratic hexahedra, 26967 dof, ~15-30 s CPU).

    Measured: plateau means of mid_szz and contact_p within 0.13 %, end_uz and rod_vz
    histories within 0.9 %, the same contact window to 1 us.
    """
    two = rod_nu0 if nu == 0.0 else rod_nu03
    three = solve(rod(nu=nu, dim=3))
    theory = rod().references["rod_theory"]
    assert three.converged and three.info["max_penetration"] <= PENETRATION
    for name, window in (("mid_szz", theory["t_mid_stress"]), ("contact_p", theory["t_contact"])):
        assert plateau_mean(three, name, window) == pytest.approx(plateau_mean(two, name, window), rel=0.01)
    for name in ("end_uz", "rod_vz"):
        assert np.abs(three.history[name] - two.history[name]).max() < 0.02 * np.abs(two.history[name]).max()
    assert three.info["contact_window"] == pytest.approx(two.info["contact_window"], abs=2e-6)
