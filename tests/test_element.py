"""Exact properties of the moment-scheme ring and prism elements."""

import numpy as np
import pytest

from cases.geometry import PRISM, RING
from helpers import distorted_mesh, patch_solution
from smfem import element
from smfem.assembly import assemble, weighted_elasticity
from smfem.constitutive import isotropic_D
from smfem.fourier import Mode
from cases.section_mesh import section_mesh
from cases.geometry import Axis, Section

D = isotropic_D(2.1e11, 0.3)


def stiffness(x, elements, body, p, integrals=(1.0, 1.0)):
    ops = element.operators(x[elements], body, 0.3)
    W = np.zeros((len(elements), 2, 2))
    W[:, 0, 0], W[:, 1, 1] = integrals
    return assemble(element.element_stiffness(ops, p, weighted_elasticity(D, W)), elements, len(x))


def energy_ratio(K, u):
    """u'Ku relative to ||K|| ||u||^2: zero to round-off for a rigid motion."""
    return abs(u @ (K @ u)) / (abs(K).max() * (u @ u))


def dome_mesh():
    from cases import get_case

    m = section_mesh(get_case("dome").section)
    return m.x, m.elements


@pytest.mark.parametrize("mesh", ["distorted", "dome"])
def test_ring_rigid_body_modes_have_zero_strain_energy(mesh):
    x, elements = distorted_mesh() if mesh == "distorted" else dome_mesh()
    r, z = x[:, 0], x[:, 1]
    one, zero = np.ones_like(r), np.zeros_like(r)
    cases = {
        # harmonic 0, symmetric family: axial translation u_z = c
        "axial translation": (0, (1.0, 0.0), np.column_stack([zero, one, zero])),
        # harmonic 0, sine family (torsion): rotation about the axis, u_theta = -V = omega r
        "rotation about the axis": (0, (0.0, 1.0), np.column_stack([zero, zero, -r])),
        # harmonic 1: lateral translation u_x = c -> u_r = c cos, u_theta = -c sin
        "lateral translation": (1, (1.0, 1.0), np.column_stack([one, zero, -one])),
        # harmonic 1: tilt about y -> u_r = z cos, u_theta = -z sin, u_z = -r cos
        "tilt": (1, (1.0, 1.0), np.column_stack([z, -r, -z])),
    }
    for name, (l, integrals, u) in cases.items():
        K = stiffness(x, elements, RING, float(l), integrals)
        assert energy_ratio(K, u.ravel()) < 1e-14, name
    # and a genuine deformation is not free: a uniform radial expansion
    K0 = stiffness(x, elements, RING, 0.0, (1.0, 0.0))
    assert energy_ratio(K0, np.column_stack([r, zero, zero]).ravel()) > 1e-6


def test_ring_harmonic_one_has_exactly_two_rigid_modes_and_two_none():
    x, elements = distorted_mesh()
    for l, nullity in ((1, 2), (2, 0)):
        ev = np.linalg.eigvalsh(stiffness(x, elements, RING, float(l)).toarray())
        assert np.sum(np.abs(ev) < 1e-12 * np.abs(ev).max()) == nullity


def test_prism_rigid_body_modes_have_zero_strain_energy():
    """With k = 0 a prism section has four rigid modes: u1, u2, u3 and rotation about x3;
    the moment scheme adds no spurious (hourglass) zero-energy mode."""
    x, elements = distorted_mesh(x1_range=(0.0, 1.0))
    K = stiffness(x, elements, PRISM, 0.0)
    x1, x2 = x[:, 0], x[:, 1]
    one, zero = np.ones_like(x1), np.zeros_like(x1)
    for u in ([one, zero, zero], [zero, one, zero], [zero, zero, one], [-x2, x1, zero]):
        assert energy_ratio(K, np.column_stack(u).ravel()) < 1e-14
    ev = np.linalg.eigvalsh(K.toarray())
    assert np.sum(np.abs(ev) < 1e-12 * np.abs(ev).max()) == 4
    ev = np.linalg.eigvalsh(stiffness(x, elements, PRISM, 3.0).toarray())
    assert np.all(ev > 1e-10 * ev.max())


def parallelogram_mesh():
    sec = Section("rect", s=Axis((1.0, 2.0), (4,)), t=Axis((0.0, 1.0), (3,)))
    mesh = section_mesh(sec)
    x = mesh.x.copy()
    x[:, 0] += 0.3 * x[:, 1]
    x[:, 1] += 0.2 * x[:, 0]
    return x, mesh.elements


@pytest.mark.parametrize("body", [RING, PRISM])
def test_patch_test_constant_strain_is_reproduced(body):
    """Boundary nodes follow a constant-strain field; the interior solution must follow it exactly.

    Prism (k = 0): any linear field on general (randomly distorted) quadrilaterals.
    Ring (harmonic 0): u_r = a r, u_z = c + d z (the linear fields with constant strain) on
    parallelograms: the scheme takes sqrt(g) = |J| r at the centre (paper: constant over the
    element), which integrates r exactly only where J is constant.
    """
    x, elements = distorted_mesh(seed=3) if body == PRISM else parallelogram_mesh()
    K = stiffness(x, elements, body, 0.0, (1.0, 0.0) if body == RING else (1.0, 1.0)).tocsr()
    x1, x2 = x[:, 0], x[:, 1]
    if body == PRISM:
        exact = np.column_stack([2e-3 * x1 + 1e-3 * x2, -1e-3 * x1 + 3e-3 * x2, 1e-3 * x1 - 2e-3 * x2]).ravel()
    else:
        exact = np.column_stack([2e-3 * x1, 1e-3 + 3e-3 * x2, 0 * x1]).ravel()
    u = patch_solution(K, exact, (4, 5), 3 if body == PRISM else 2)  # ring harmonic 0, symmetric: no u_theta
    assert np.abs(u - exact).max() < 1e-12 * np.abs(exact).max()


def test_complex_step_derivatives_match_finite_differences():
    x, elements = distorted_mesh(seed=5)
    X = x[elements]
    ops = element.operators(X, RING, 0.3)
    B0, B1, B2 = (a + 2.0 * b for a, b in zip(ops.Ba, ops.Bb))
    T = element.strain_rotation(ops.rotation)
    h = 1e-6
    local = lambda xi, eta: np.einsum("ers,esk->erk", T, element.strain_operator(X, RING, 2.0, xi, eta))
    assert np.allclose(B0, local(0.0, 0.0))
    assert np.allclose(B1, (local(h, 0.0) - local(-h, 0.0)) / (2 * h), rtol=1e-6, atol=1e-6 * np.abs(B1).max())
    assert np.allclose(B2, (local(0.0, h) - local(0.0, -h)) / (2 * h), rtol=1e-6, atol=1e-6 * np.abs(B2).max())
