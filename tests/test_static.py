"""Static verification: Lame, the exact hinged strip, and freedom from locking."""

import dataclasses

import numpy as np
import scipy.sparse.linalg as sla
import pytest

from cases import get_case
from cases.analytic import hinged_strip_sine, lame_cylinder
from cases.geometry import Pressure
from helpers import clamped_plate, dome_apex_static, nearest_node, static_solution, thick_cylinder_internal_pressure


def lame_error(refine, nu=0.0):
    case = thick_cylinder_internal_pressure(1e6, refine=refine, nu=nu)
    model, (u,) = static_solution(case)
    r = model.mesh.x[:, 0]
    exact = lame_cylinder(r, 1.0, 2.0, 1e6, 0.0, case.material.E, nu)["u_r"]
    return np.abs(u[:, 0] - exact).max() / np.abs(exact).max()


@pytest.mark.parametrize("nu", [0.0, 0.3])
def test_thick_cylinder_against_lame_converges_at_second_order(nu):
    errors = [lame_error(r, nu) for r in (1, 2, 4, 8)]
    assert errors[0] < 0.005  # the paper mesh: within 0.5 %
    slopes = -np.diff(np.log(errors)) / np.log(2)
    assert np.all(slopes > 1.9), slopes


def strip_case(refine):
    case = get_case("notched_strip", {"notch_depth": 0.0, "plastic": False, "refine": refine, "harmonics": 1})
    return dataclasses.replace(case, loads=(Pressure(1e6, "top", mode=1),))


def test_hinged_strip_sine_load_against_exact_elasticity():
    """Plane-strain strip, h/L = 1/3, against the Airy-function solution of cases.analytic."""
    errors = []
    for refine in (1, 2, 4):
        model, (u,) = static_solution(strip_case(refine))
        x2 = model.mesh.x[:, 1]
        exact = hinged_strip_sine(0.15, x2, 0.3, 0.1, 1e6, 2.1e11, 0.3)["u_z"]  # mid-span: sin = 1
        errors.append(np.abs(u[:, 1] - exact).max() / np.abs(exact).max())
    assert errors[0] < 0.002
    assert np.all(-np.diff(np.log(errors)) / np.log(2) > 1.9)


def test_dome_paper_mesh_is_within_two_percent_of_four_times_refined():
    coarse, fine = dome_apex_static(0.41), dome_apex_static(0.41, refine=4)
    assert abs(coarse / fine - 1) < 0.02
    full = dome_apex_static(0.41, scheme="full")
    assert abs(full / fine - 1) > 4 * abs(coarse / fine - 1)


def test_thin_dome_error_is_resolution_of_the_edge_layer_not_locking():
    """R/h = 543 (thickness / 10): the clamped edge's bending layer (width ~ sqrt(R h)) is
    sqrt(10) times narrower, so 20 elements along the meridian no longer resolve it.

    Locking would depend on the elements' aspect ratio; this error does not: more elements
    through the thickness change nothing, fewer do not hurt, and more along the meridian
    remove it at the rate of a smooth problem. The fully integrated bilinear element is
    markedly worse on the same mesh.
    """
    h = 0.041
    fine = dome_apex_static(h, n_thick=8, n_meridian=320)
    err = lambda **mesh: abs(dome_apex_static(h, **mesh) / fine - 1)
    paper = err()
    assert abs(err(n_thick=8) - paper) < 0.002  # through-thickness refinement: no change
    assert err(n_thick=1, n_meridian=64) < 0.02  # one element through the thickness suffices
    assert err(n_meridian=40) < 0.021 and err(n_meridian=64) < 0.01  # the meridian resolves it
    full = abs(dome_apex_static(h, scheme="full") / fine - 1)
    assert full > 2.5 * paper


def test_clamped_plate_does_not_lock_and_the_full_element_does():
    """Centre deflection over Kirchhoff's q a^4 / (64 D) for a/h = 100 and 1000.

    (At a/h = 1e4 a continuum model of a plate in double precision is past its conditioning:
    cond(K) ~ 3e17, whatever the element.)
    """
    ratios = {}
    for h in (1e-1, 1e-2):
        for scheme in ("moment", "full"):
            case = clamped_plate(h)
            model, (u,) = static_solution(case, scheme=scheme)
            E, nu = case.material.E, case.material.nu
            w0 = 10.0**4 / (64 * E * h**3 / (12 * (1 - nu**2)))
            ratios[h, scheme] = -u[nearest_node(model, 0.0, 0.0), 1] / w0
    assert abs(ratios[1e-2, "moment"] - 1) < 0.03 and abs(ratios[1e-2, "moment"] - ratios[1e-1, "moment"]) < 2e-3
    assert ratios[1e-1, "full"] < 0.25 and ratios[1e-2, "full"] < 0.01


def test_stress_probes_against_lame_and_the_exact_strip():
    """Stress probes by synthesis: hoop stress in the cylinder, bending stress in the strip."""
    from cases.geometry import Probe
    from smfem.probes import ProbeSet

    case = thick_cylinder_internal_pressure(1e6, nu=0.3, refine=2)
    model, _ = static_solution(case)
    s = model.systems[0]
    u = sla.spsolve(s.K.tocsc(), s.Q)
    r = 1.0 + 7.5 / 30  # an element centre: where the moment scheme's stresses are sharpest
    probes = ProbeSet(model, [Probe("s_tt", "point", "sigma", (3, 3), point=(r, 0.0, 0.3)),
                              Probe("s_rr", "point", "sigma", (1, 1), point=(r, 0.0, 0.3))])
    exact = lame_cylinder(r, 1.0, 2.0, 1e6, 0.0, case.material.E, 0.3)
    s_tt, s_rr = probes.evaluate(u, u)
    assert s_tt == pytest.approx(exact["sigma_tt"], rel=2e-3)
    assert s_rr == pytest.approx(exact["sigma_rr"], abs=2e-3 * exact["sigma_tt"])

    model, _ = static_solution(strip_case(2))
    s = model.systems[0]
    u = sla.spsolve(s.K.tocsc(), s.Q)
    z = 0.1 * (1 - 0.5 / 40)  # centre of the top element row
    probes = ProbeSet(model, [Probe("s_span", "point", "sigma", (3, 3), point=(0.0025, z, 0.15))])
    exact = hinged_strip_sine(0.15, z, 0.3, 0.1, 1e6, 2.1e11, 0.3)["sigma_xx"]
    assert probes.evaluate(u, u)[0] == pytest.approx(exact, rel=5e-3)
