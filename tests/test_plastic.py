"""Wilkins plasticity and the block-iterative solver."""

import math

import numpy as np
import pandas as pd
import pytest

from cases import get_case
from cases.material import lame
from smfem.model import Model
from smfem.options import SolverOptions
from smfem.plasticity import intensity, shear_intensity, wilkins
from smfem.solver import solve


def uniaxial_strain_path(E, nu, sigma_y, E_T, strains):
    """Drive one point through uniaxial strain increments; return sigma_11 and peps."""
    lam, mu = lame(E, nu)
    H = E * E_T / (E - E_T) if E_T else 0.0
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[[0, 1, 2], [0, 1, 2]] += 2 * mu
    D[[3, 4, 5], [3, 4, 5]] = mu
    sigma, alpha, eps_p, out = np.zeros(6), np.array(0.0), np.zeros(6), []
    prev = 0.0
    for e in strains:
        d = np.zeros(6)
        d[0] = e - prev
        prev = e
        sigma, alpha, deps_p, _ = wilkins(sigma + D @ d, alpha, np.array(mu), sigma_y, H)
        eps_p = eps_p + deps_p
        out.append((sigma[0], sigma[1], float(alpha), float(intensity(eps_p))))
    return np.array(out), lam, mu, H


@pytest.mark.parametrize("E_T", [0.0, 0.21e6])
def test_uniaxial_strain_follows_the_hardening_law_exactly(E_T):
    """In uniaxial strain the stress difference follows the yield stress,
    sigma_11 - sigma_22 = sigma_y0 + H peps, with peps = (2/3)(eps - eps_y) 3 mu / (3 mu + H)."""
    E, nu, sy = 10.5e6, 0.3, 24000.0
    strains = np.linspace(0, 0.02, 201)[1:]
    path, lam, mu, H = uniaxial_strain_path(E, nu, sy, E_T, strains)
    s11, s22, peps, peps_tensor = path.T
    assert np.allclose(peps_tensor, peps, rtol=1e-12, atol=1e-18)  # proportional: intensity = accumulated
    eps_y = sy / (2 * mu)  # sigma_11 - sigma_22 = 2 mu eps in the elastic range
    plastic = strains > eps_y
    assert np.all(peps[~plastic] == 0)
    assert np.allclose((s11 - s22)[plastic], sy + H * peps[plastic], rtol=1e-12)
    expected = (2 / 3) * (strains[plastic] - eps_y) * 3 * mu / (3 * mu + H)
    assert np.allclose(peps[plastic], expected, rtol=1e-10)
    voigt = np.column_stack([s11, s22, s22, 0 * s11, 0 * s11, 0 * s11])  # uniaxial strain: s33 = s22
    assert np.allclose(math.sqrt(3) * shear_intensity(voigt)[plastic], sy + H * peps[plastic], rtol=1e-12)


def test_plastic_strain_intensity_falls_under_reversed_flow_while_hardening_does_not():
    strains = np.concatenate([np.linspace(0, 0.01, 101)[1:], np.linspace(0.01, -0.004, 151)[1:]])
    path, *_ = uniaxial_strain_path(10.5e6, 0.3, 24000.0, 0.21e6, strains)
    alpha, peps = path[:, 2], path[:, 3]
    assert np.all(np.diff(alpha) >= 0) and peps[-1] < peps[99] < alpha[-1]


def test_wilkins_leaves_the_mean_stress_and_elastic_points_alone():
    rng = np.random.default_rng(2)
    trial = rng.normal(size=(50, 6)) * 1.2e8
    sigma, peps, deps_p, yielding = wilkins(trial, np.zeros(50), np.full(50, 8e10), 2.9e8, 0.0)
    assert np.allclose(intensity(deps_p), peps)  # one step: the increment's intensity
    assert np.allclose(sigma[:, :3].mean(1), trial[:, :3].mean(1))
    assert np.allclose(sigma[~yielding], trial[~yielding])
    assert np.allclose(math.sqrt(3) * shear_intensity(sigma[yielding]), 2.9e8)
    assert np.all(peps[yielding] > 0) and yielding.any() and (~yielding).any()


@pytest.mark.parametrize("name,keys", [("thick_cylinder", {"q": 1e6}), ("notched_cylinder", {"q": 1e6})])
def test_iterative_path_reproduces_the_linear_solver_below_yield(name, keys):
    """A plastic run whose load never reaches yield is the elastic run: the iterative solver
    (more harmonics, sample points, Wilkins) against the direct linear one."""
    t_end = 2e-3 if name == "thick_cylinder" else 6e-3
    plastic = solve(get_case(name, {"plastic": True, "t_end": t_end, **keys}), with_fields=False)
    elastic = solve(get_case(name, {"plastic": False, "t_end": t_end, **keys}), with_fields=False)
    assert plastic.converged and max(plastic.history["peps_max"]) == 0
    for probe, h in elastic.history.items():
        assert np.abs(plastic.history[probe] - h).max() < 1e-4 * np.abs(h).max(), probe


def test_plastic_thick_cylinder_yields_and_converges_in_few_iterations():
    result = solve(get_case("thick_cylinder", {"plastic": True}), with_fields=False)
    assert result.converged and len(result.iterations) == 100
    assert result.info["iterations_max"] <= 8 and result.info["iterations_mean"] < 4
    peps_A, peps_max = result.history["peps_A"], result.history["peps_max"]
    assert peps_max.max() > 1e-3 and np.all(np.diff(peps_max) >= -1e-15)  # accumulates, never drops
    assert 0 < peps_A.max() <= peps_max.max()
    assert result.info["harmonics_used"] == [f"{l}c" for l in range(0, 20, 2)]


def test_not_converged_step_is_reported_with_the_history_kept():
    result = solve(get_case("thick_cylinder", {"plastic": True}), SolverOptions(max_iterations=2), with_fields=False)
    assert not result.converged and "did not converge" in result.message and "t = " in result.message
    assert len(result.history["A_ur"]) == len(result.iterations) + 1 and 0 < len(result.iterations) < 100


def test_cli_exit_3_when_a_step_does_not_converge(monkeypatch, tmp_path, capsys):
    import pandas as pd

    from smfem.cli import main

    monkeypatch.setattr("smfem.solver.SolverOptions", lambda: SolverOptions(max_iterations=2))
    assert main(["run", "thick_cylinder", "--set", "plastic=true", "--out", str(tmp_path), "--quiet"]) == 3
    assert "did not converge" in capsys.readouterr().err
    assert 1 < len(pd.read_csv(tmp_path / "history.csv")) < 101


def test_plastic_run_writes_the_plastic_zones_at_the_paper_times(tmp_path):
    import matplotlib.image as mpimg

    from smfem.cli import main

    assert main(["run", "notched_strip", "--set", "harmonics=20", "--out", str(tmp_path), "--quiet"]) == 0
    image = mpimg.imread(tmp_path / "plastic_zones.png")
    assert image.shape[0] > 300 and image.shape[1] > 600
    result = solve(get_case("notched_strip", {"harmonics": 20}), with_fields=False)
    assert [round(s.t, 9) for s in result.snapshots] == [0.96e-4, 3.2e-4]
    late = result.snapshots[-1].peps
    assert (late >= 1e-3).sum() > (result.snapshots[0].peps >= 1e-3).sum() > 0  # the hinge grows


def test_stacked_solve_of_a_homogeneous_body_equals_the_papers_block_sweep():
    """A body homogeneous along x3: its harmonics do not couple through the stiffness, so the
    block Gauss-Seidel sweep is block Jacobi, which one block-diagonal solve of all harmonics
    does at once. Without acceleration: the same iterations, the same histories to round-off."""
    case = get_case("thick_cylinder", {"plastic": True, "t_end": 2.4e-3})
    stacked = solve(case, SolverOptions(anderson=0), with_fields=False)
    sweep = solve(case, SolverOptions(iteration_matrix="sor"), with_fields=False)
    assert "one block-diagonal solve" in stacked.info["solve"] and "block SOR" in sweep.info["solve"]
    assert stacked.iterations == sweep.iterations and max(stacked.history["peps_max"]) > 1e-3
    for name, h in stacked.history.items():
        assert np.abs(h - sweep.history[name]).max() <= 1e-10 * np.abs(sweep.history[name]).max(), name


def test_anderson_acceleration_reaches_the_same_solution_in_fewer_iterations():
    """The notched strip's plastic iterations at a tight tolerance: Anderson acceleration (the
    default, 5 iterates) against the plain iteration. Measured (40 harmonics, 40 steps):
    6.8 against 12.5 iterations per step, probes equal to 2e-6 (peps_top 1.5e-4)."""
    case = get_case("notched_strip", {"tol": 1e-8, "t_end": 1.28e-4, "harmonics": 40})
    fast, plain = solve(case, with_fields=False), solve(case, SolverOptions(anderson=0), with_fields=False)
    assert fast.converged and fast.info["iterations_mean"] < 0.6 * plain.info["iterations_mean"]
    for name, h in plain.history.items():
        assert np.abs(fast.history[name] - h).max() <= 1e-3 * np.abs(h).max(), name


@pytest.mark.parametrize("name, sets, width, copies", [
    ("notched_strip", {"harmonics": 20}, 0.15, 2), ("notched_cylinder", {"harmonics": 20}, math.pi / 2, 4),
    ("thick_cylinder", {"plastic": True}, math.pi / 2, 4), ("dome", {"plastic": True}, 0.0, 1)])
def test_elastic_forces_at_the_sample_points_are_K_u_over_the_fundamental_domain(name, sets, width, copies):
    """The stress points cover only the modes' fundamental domain along x3 (half the strip's
    span, a quarter of the cylinders, one point of the axisymmetric dome), weighted for all
    its images, and the x3 rule there is exact: the forces of the elastic stresses
    of any amplitudes are K u with the exact coupling. The images tile the period."""
    from smfem.coupling import StackedOperator
    from smfem.sampling import SamplePoints

    model = Model(get_case(name, sets), nonlinear=True)
    points = SamplePoints(model, oversampling=1.0)
    assert points.symmetry.width == pytest.approx(width) and points.symmetry.copies == copies
    u = np.random.default_rng(3).normal(size=model.n_dof)
    Ku = StackedOperator(model).K(u)
    assert np.abs(points.forces(points.stress(u)) - Ku).max() <= 1e-10 * np.abs(Ku).max()
    full, index, mirrored = points.symmetry.images(points.x3)
    period = 2 * math.pi if model.body == "ring" else model.length
    assert len(full) == copies * len(points.x3) and mirrored.sum() == (len(full) // 2 if points.symmetry.mirror else 0)
    assert width == 0 or (np.all(np.diff(full) > 0) and 0 < full[0] and full[-1] < period)


def test_turned_cutouts_break_the_reflection_of_the_sample_points():
    """Cut-outs turned by 30 deg: both families, no mirror symmetry; the cut-outs still repeat
    every half turn, so the points cover half the circle."""
    import dataclasses

    from cases.geometry import Cutout
    from smfem.sampling import SamplePoints

    case = get_case("notched_cylinder", {"harmonics": 12})
    c = case.cutouts[0]
    turned = dataclasses.replace(case, cutouts=(Cutout(c.s_range, c.t_range, tuple(
        (a + math.pi / 6, b + math.pi / 6) for a, b in c.x3_intervals)),))
    points = SamplePoints(Model(turned, nonlinear=True), oversampling=1.0)
    assert not points.symmetry.mirror and points.symmetry.width == pytest.approx(math.pi)


def test_more_stress_points_along_x3_change_the_probes_little():
    """The plastic strains are sampled at the exact count of Gauss-Legendre points along x3
    (x3_oversampling 1); three times as many move the strip's probes by little. Measured (40
    harmonics, 50 steps, 62 against 186 points): mid_uz 9e-5, peps_top 1.1e-3, peps_notch (on
    the notch line, where the hinge localizes) 9e-3 of their largest values."""
    case = get_case("notched_strip", {"harmonics": 40, "t_end": 1.6e-4, "tol": 1e-10})
    one, three = (solve(case, SolverOptions(x3_oversampling=o), with_fields=False) for o in (1.0, 3.0))
    assert three.info["n_x3_points"] >= 3 * one.info["n_x3_points"] - 3
    for name, h in three.history.items():
        tol = 2e-4 if name == "mid_uz" else 2e-2
        assert np.abs(one.history[name] - h).max() <= tol * np.abs(h).max(), name


def test_the_return_map_touches_only_the_points_that_yield():
    from smfem.plasticity import return_map_rows

    rng = np.random.default_rng(5)
    trial = rng.normal(scale=1e8, size=(6, 200))
    alpha, mu = np.zeros(200), np.full(200, 8e10)
    sigma, alpha_new, at, deps = return_map_rows(trial, alpha, mu, 2.9e8, 0.0)
    elastic = np.setdiff1d(np.arange(200), at)
    assert 0 < len(at) < 200 and deps.shape == (6, len(at))
    assert np.array_equal(sigma[:, elastic], trial[:, elastic]) and np.all(alpha_new[elastic] == 0)
    assert np.allclose(math.sqrt(3) * shear_intensity(sigma[:, at].T), 2.9e8, rtol=1e-12)
    calm = trial * 1e-3
    assert return_map_rows(calm, alpha, mu, 2.9e8, 0.0)[0] is calm


def test_the_stress_points_along_x3_are_the_measured_multiple_of_the_exact_count():
    """cases/x3_points.csv (benchmarks/x3_points.py --write) holds, per plastic scene and
    harmonic count, the multiple of the exact count whose plastic-zone area one more doubling
    moves by at most 1 %; a plastic run takes it (the nearest measured count otherwise), a scene
    without a row the exact count, and an explicit x3_oversampling wins."""
    from cases import x3_points
    from smfem.sampling import SamplePoints

    table = pd.read_csv(x3_points.TABLE)
    assert (table.area_change_pct <= 100 * x3_points.AREA_TOLERANCE).all()  # every row met the rule
    assert set(table.factor) <= {1, 2, 4, 8, 16} and (table.points >= table.exact_points).all()
    row = table[(table.scene == "notched_cylinder") & (table.harmonics == 40)].iloc[0]
    model = Model(get_case("notched_cylinder", {"harmonics": 40}), nonlinear=True)
    assert len(SamplePoints(model, 1.0).x3) == row.exact_points
    r = solve(get_case("notched_cylinder", {"harmonics": 40, "t_end": 1e-4}), with_fields=False)
    assert r.info["n_x3_points"] == row.points and r.info["x3_oversampling"] == row.factor
    assert x3_points.oversampling("notched_cylinder", 41)[0] == row.factor  # nearest measured count
    assert x3_points.oversampling("no such scene", 40)[0] == 1.0
    r = solve(get_case("notched_cylinder", {"harmonics": 40, "t_end": 1e-4}), SolverOptions(x3_oversampling=1.0),
              with_fields=False)
    assert r.info["n_x3_points"] == row.exact_points

def test_anderson_by_its_normal_equations_is_the_least_squares_combination():
    """smfem.iterative.Anderson keeps its differences in ring buffers and solves the normal
    equations on unit columns: each next iterate equals the one a least squares solve of the
    whole difference matrix gives (Walker & Ni's type II), before and after the buffer wraps."""
    from smfem.iterative import Anderson

    rng = np.random.default_rng(3)
    A = np.eye(40) + 0.05 * rng.standard_normal((40, 40))
    b = rng.standard_normal(40)
    fast, xs, fs = Anderson(3), [], []
    x = np.zeros(40)
    for _ in range(8):
        f = b - A @ x
        xs.append(x), fs.append(f)
        nxt = fast.next(x, f)
        dX = np.column_stack([xs[i + 1] - xs[i] for i in range(len(xs) - 1)][-3:]) if len(xs) > 1 else None
        dF = np.column_stack([fs[i + 1] - fs[i] for i in range(len(fs) - 1)][-3:]) if len(fs) > 1 else None
        expected = x + f if dF is None else x + f - (dX + dF) @ np.linalg.lstsq(dF, f, rcond=None)[0]
        assert np.allclose(nxt, expected, rtol=1e-9, atol=1e-12)
        x = nxt
    assert np.linalg.norm(b - A @ x) < 1e-3 * np.linalg.norm(b)  # and the residual falls (5e-5 in 8)
    assert np.array_equal(Anderson(0).next(np.ones(3), np.ones(3)), 2 * np.ones(3))
