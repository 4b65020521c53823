"""Reference FEM, exact and analytic static checks: meshes, Lame, patch test, plasticity, Hill."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from skfem import asm, condense, solve as skfem_solve
from skfem.models.elasticity import linear_elasticity

from cases import get_case
from cases.analytic import hill_cylinder, lame_cylinder
from cases.case import Case
from cases.geometry import RING, Axis, Pressure, Section, Support
from cases.material import Material
from reference_fem import Model, static
from reference_fem.equilibrium import NotConverged
from reference_fem.probes import Probes

CASES = ["dome", "thick_cylinder", "notched_cylinder", "notched_strip", "rod_impact"]


def section_volume(name: str, dim: int) -> float:
    """Exact volume (3D) or section area (2D: annulus, half-plane section or span x height)."""
    from cases import dome, notched_cylinder as nc, notched_strip as ns, rod_impact as rod, thick_cylinder as tc

    if name == "dome":
        ro, ri, a = dome.R + dome.H / 2, dome.R - dome.H / 2, math.radians(dome.HALF_ANGLE_DEG)
        return 2 * math.pi / 3 * (1 - math.cos(a)) * (ro**3 - ri**3) if dim == 3 else a * (ro**2 - ri**2) / 2
    if name == "thick_cylinder":
        area = math.pi * (tc.R2**2 - tc.R1**2)
        return area * (tc.R2 - tc.R1) / tc.N_R if dim == 3 else area
    if name == "notched_cylinder":
        area = math.pi * (nc.R3**2 - nc.R1**2) - math.pi / 2 * (nc.R2**2 - nc.R1**2)
        return area * (nc.R2 - nc.R1) / 4 if dim == 3 else area
    if name == "notched_strip":
        area = ns.L * ns.H - 0.01 * 0.025
        return area * ns.H / ns.N_Z if dim == 3 else area
    return math.pi * rod.RADIUS**2 * rod.LENGTH if dim == 3 else rod.RADIUS * rod.LENGTH


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("name", CASES)
def test_mesh_volume_and_holes(name, dim):
    """Curved quadratic meshes reproduce the exact volume; cut-outs and the notch are holes."""
    model = Model(get_case(name, {"dim": dim}))
    assert (model.basis.dx > 0).all()
    # vector dofs interleave the components node by node (probes, outputs rely on it)
    for k in range(model.dim):
        np.testing.assert_allclose(model.basis.doflocs[:, k :: model.dim], model.rmesh.mesh.doflocs)
    volume = model.weights.sum() if model.rep != "axisymmetric" else model.basis.dx.sum()
    # O-grids (3D dome and rod) interpolate the circumference with 32 and 8 quadratic elements
    tol = {("rod_impact", 3): 2e-3, ("dome", 3): 1e-5}.get((name, dim), 1e-6)
    assert volume == pytest.approx(section_volume(name, dim), rel=tol)


@pytest.mark.parametrize("overrides", [{}, {"dim": 3}, {"nu": 0.3}])
def test_strain_operator_matches_skfem_elasticity(overrides):
    """B^T D B equals scikit-fem's own linear elasticity form (plane strain and 3D)."""
    model = Model(get_case("thick_cylinder", overrides))
    K = asm(linear_elasticity(model.lam, model.mu), model.basis)
    assert abs(model.stiffness() - K).max() < 1e-9 * abs(K).max()


@pytest.mark.parametrize("dim", [2, 3])
def test_lame_thick_cylinder(dim):
    """Uniform internal pressure: radial displacement at r1 and r2 within 0.1 % of Lame."""
    p = 1e6
    case = get_case("thick_cylinder", {"dim": dim, "nu": 0.3})
    case = dataclasses.replace(case, loads=(Pressure(p, "inner", ((0.0, 2 * math.pi),)),))
    model, (u,), _, system = static(case)
    values = dict(zip([q.name for q in case.probes], Probes(model).values(u, system)))
    exact = lame_cylinder(np.array([2.0, 1.0]), 1.0, 2.0, p, 0.0, case.material.E, case.material.nu)["u_r"]
    assert values["A_ur"] == pytest.approx(exact[0], rel=1e-3)
    assert values["C_ur"] == pytest.approx(exact[1], rel=1e-3)
    assert abs(values["B_ut"]) < 1e-9 * exact[0]
    # the hoop stress at the quadrature point nearest the inner surface as well
    x = model.x_qp
    q = np.argmin(np.hypot(*x[:2]))
    r = np.hypot(*x[:2, q])
    lame = lame_cylinder(r, 1.0, 2.0, p, 0.0, case.material.E, case.material.nu)
    c, s = x[:2, q] / r
    sig = system.sigma[q]
    hoop = s * s * sig[0] + c * c * sig[1] - np.sqrt(2) * s * c * sig[-1]  # Mandel xy is last
    # 3D runs half the radial elements of 2D (stresses converge one order slower than u)
    assert hoop == pytest.approx(lame["sigma_tt"], rel=1e-3 if dim == 2 else 5e-3)


def test_axisymmetric_patch_test():
    """u_r = a r, u_z = c z + e on the dome's curved 2D mesh: interior nodes exact, stress uniform."""
    model = Model(get_case("dome"))
    a, c, e = 1e-3, -2e-3, 0.5
    x = model.basis.doflocs
    exact = np.where(np.arange(model.basis.N) % 2 == 0, a * x[0], c * x[1] + e)
    boundary = model.basis.get_dofs().flatten()
    u = skfem_solve(*condense(model.stiffness(), np.zeros(model.basis.N), x=exact, D=boundary))
    assert np.abs(u - exact).max() < 1e-10 * np.abs(exact).max()
    sigma = (model.B @ u).reshape(model.n_qp, -1) @ model.D
    expected = np.array([a, c, a, 0.0]) @ model.D
    assert np.abs(sigma - expected).max() < 1e-8 * np.abs(expected).max()


def uniaxial_strain_case(E_T: float) -> Case:
    """One axisymmetric quadratic element, u_r = 0 everywhere: uniaxial strain along z."""
    params = dict(dt=1.0, t_end=1.0, refine=1, harmonics=1, tol=1e-12, dim=2)
    section = Section("rect", s=Axis((0.0, 1.0), (1,)), t=Axis((0.0, 1.0), (1,)),
                      edges={"bottom": "t_min", "top": "t_max"})
    return Case(
        name="unit", title="uniaxial strain", body=RING, section=section,
        material=Material(2.0e11, 0.3, 1.0, tau_s=1.0e8, E_T=E_T, plastic=True),
        loads=(Pressure(-1.0, "top", ((0.0, 2 * math.pi),)),),
        supports=(Support("all", (1,)), Support("bottom", (2,))), probes=(), params=params,
        axisymmetric=True,
    )


@pytest.mark.parametrize("E_T", [2.0e10, 0.0])
def test_uniaxial_strain_hardening_law(E_T):
    """Tension to 3 x first yield, then partial unloading: strain and plastic strain exact."""
    case = uniaxial_strain_case(E_T)
    mat = case.material
    lam, mu = mat.lame
    K, H, sy = lam + 2 * mu / 3, mat.hardening_modulus, mat.sigma_y
    s_first = (lam + 2 * mu) * sy / (2 * mu)  # sigma_zz at first yield

    def loading(s):
        """(eps_zz, peps) on the loading branch; with ideal plasticity the mean stress still grows."""
        if s <= s_first:
            return s / (lam + 2 * mu), 0.0
        eps = (s - 2 * sy * mu / (3 * mu + H)) / (K + 4 * H * mu / (3 * (3 * mu + H)))
        return eps, (2 * mu * eps - sy) / (3 * mu + H)

    up = s_first * np.array([0.5, 1.0, 1.5, 2.0, 3.0])
    down = s_first * np.array([2.0, 1.5])  # unloading stays elastic: the deviator drops < 2 sigma_y
    peak_eps, peak_p = loading(up[-1])
    expected = [loading(s) for s in up] + [(peak_eps - (up[-1] - s) / (lam + 2 * mu), peak_p) for s in down]
    model, us, its, system = static(case, np.concatenate([up, down]))
    top = np.isclose(model.basis.doflocs[1], 1.0) & (np.arange(model.basis.N) % 2 == 1)
    for u, (eps, _) in zip(us, expected):
        assert u[top] == pytest.approx(np.full(top.sum(), eps), rel=1e-9)
    assert system.peps == pytest.approx(np.full(model.n_qp, peak_p), rel=1e-9)
    assert its[:2] == [1, 1] and min(its[2:5]) > 1 and its[5:] == [1, 1]


@pytest.fixture(scope="module")
def hill_run():
    """Internal pressure on the plane-strain cylinder, nu = 0.49 (Hill: incompressible)."""
    E, nu, k = 2.1e11, 0.49, 1.7e8
    case = get_case("thick_cylinder", {"plastic": True, "nu": nu, "tol": 1e-8})
    case = dataclasses.replace(case, loads=(Pressure(1.0, "inner", ((0.0, 2 * math.pi),)),))
    ref = hill_cylinder(0.0, 1.0, 2.0, k, E, nu)
    p_y, p_c = float(ref["p_y"]), float(ref["p_c"])
    pressures = np.concatenate([[0.5 * p_y, 0.99 * p_y, 1.03 * p_y],
                                p_y + (p_c - p_y) * np.array([0.2, 0.4, 0.6, 0.8, 0.9, 0.95, 0.98, 0.995])])
    model, us, its, system = static(case, pressures)
    probes = Probes(model)
    u_b = np.array([probes.values(u, system)[0] for u in us])
    return dict(case=case, model=model, pressures=pressures, u_b=u_b, its=its, p_y=p_y, p_c=p_c,
                ref=hill_cylinder(pressures, 1.0, 2.0, k, E, nu), system=system)


def test_hill_first_yield_and_curve(hill_run):
    """Elastic below p_y, plastic above; the outer displacement follows Hill's curve within 1 %.

    The first Gauss point sits at r = 1.0075 (3 points in the first of 15 elements), where
    sigma_tt - sigma_rr ~ 1 / r^2 is 1.5 % lower than at r = 1: yield starts there at 1.015 p_y.
    """
    h = hill_run
    its = np.array(h["its"])
    assert np.all(its[h["pressures"] < h["p_y"]] == 1)
    assert np.all(its[h["pressures"] > h["p_y"]] > 1)
    np.testing.assert_allclose(h["u_b"], h["ref"]["u_b"], rtol=1e-2)


def test_hill_collapse(hill_run):
    """Above the collapse pressure 2 k ln(b / a) there is no bounded equilibrium.

    Newton either fails, or (the displacement criterion ||du|| / ||u|| < tol being blind to a
    mechanism) accepts a runaway displacement: both mean collapse.
    """
    h = hill_run
    u_c = float(hill_cylinder(h["p_c"], 1.0, 2.0, 1.7e8, 2.1e11, 0.49)["u_b"])
    assert h["u_b"][-1] < 1.01 * u_c  # 0.995 p_c still carried
    try:
        model, us, _, system = static(h["case"], np.concatenate([h["pressures"], [1.01 * h["p_c"]]]))
    except NotConverged:
        return
    assert Probes(model).values(us[-1], system)[0] > 10 * u_c
