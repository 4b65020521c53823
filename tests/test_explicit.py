"""The explicit truth engine (``reference_fem/explicit.py``): central differences on the HRZ
lumped mass, checked where the answer is known."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as la

from cases import get_case
from reference_fem.explicit import ExplicitSystem, critical_step, largest_frequency, march, solve
from reference_fem.mass import consistent_mass, lumped_mass
from reference_fem.model import Model
from reference_fem.probes import Probes


@pytest.mark.parametrize("name", ["dome", "rod_impact", "notched_cylinder"])
def test_lumped_mass_is_positive_and_keeps_the_mass(name):
    """HRZ lumping: no zero or negative entry (the axis nodes of the axisymmetric dome and rod
    included), and the consistent mass's total in every component."""
    case = get_case(name)
    model = Model(case)
    axisym = model.rep == "axisymmetric"
    lumped = lumped_mass(model.basis, case.material.rho, axisym)
    total = consistent_mass(model.basis, case.material.rho, axisym) @ np.ones(model.basis.N)
    assert lumped.min() > 0
    for c in range(model.dim):
        assert lumped[c :: model.dim].sum() == pytest.approx(total[c :: model.dim].sum(), rel=1e-12)


class _Chain:
    """A fixed-free chain of unit masses and springs: the smallest system :func:`march` takes."""

    def __init__(self, n: int = 6, k: float = 1.0):
        self.K = k * (2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1))
        self.K[-1, -1] = k
        self.m = np.ones(n)

    def internal_forces(self, u):
        return self.K @ u

    def constrain(self, u):
        return np.zeros_like(u)


def test_central_differences_are_second_order():
    """Free vibration of the chain from an initial velocity against its modal solution: the
    error at t = 10 falls four times per halving of the step."""
    chain = _Chain()
    v0 = np.linspace(0.5, 1.0, chain.m.size)
    w2, phi = la.eigh(chain.K)
    exact = phi @ (phi.T @ v0 / np.sqrt(w2) * np.sin(np.sqrt(w2) * 10.0))
    errors = []
    for n in (200, 400, 800, 1600):
        *_, (_, _, u, _, _) = march(chain, np.zeros_like(v0), v0, 10.0 / n, n)
        errors.append(np.abs(u - exact).max())
    orders = np.log2(np.array(errors[:-1]) / errors[1:])
    assert np.all(np.abs(orders - 2.0) < 0.05), orders


def test_stable_below_the_critical_step_and_unstable_above():
    """The thick cylinder's model (r1, lumped): under the step load, 3000 steps at 0.98 of
    2 / omega_max stay near the static deflection; at 1.02 the highest mode grows without
    bound (omega_max from Lanczos, so the bound is the model's own)."""
    model = Model(get_case("thick_cylinder"), lumped=True)
    system = ExplicitSystem(model)
    dt_cr = critical_step(largest_frequency(system.K, system.m))
    Q = model.Q[model.free]
    zero = np.zeros_like(Q)
    peak = {}
    for fraction in (0.98, 1.02):
        with np.errstate(over="ignore", invalid="ignore"):
            peak[fraction] = max(np.abs(u).max() for _, _, u, _, _ in march(system, Q, zero, fraction * dt_cr, 3000))
    static = np.abs(np.linalg.solve(system.K.toarray(), Q)).max()
    assert peak[0.98] < 5 * static
    assert not peak[1.02] < 1e6 * static  # NaN or overflow counts as unbounded


def test_rigid_rod_theory_for_nu_zero():
    """nu = 0: the 1-D rod theory is exact (Case 5): the contact stress is -rho c v0 for
    2 L / c, the stress passes mid-length during [L / 2c, 3 L / 2c], the rod leaves at v0.
    Measured at refine 2: plateau -0.01 %, mid-length -0.08 %, rebound -0.2 %."""
    case = get_case("rod_impact", {"nu": 0.0, "refine": 2})
    theory = case.references["rod_theory"]
    run = solve(case)
    t, h = run.t, run.history
    margin = 2e-5  # the ringing at the fronts
    inside = (t > theory["t_contact"][0] + margin) & (t < theory["t_contact"][1] - margin)
    assert h["contact_p"][inside].mean() == pytest.approx(theory["stress"], rel=2e-3)
    mid = (t > theory["t_mid_stress"][0] + margin) & (t < theory["t_mid_stress"][1] - margin)
    assert h["mid_szz"][mid].mean() == pytest.approx(theory["stress"], rel=5e-3)
    assert h["rod_vz"][-1] == pytest.approx(theory["rebound_velocity"], rel=5e-3)
    pressed = t[h["contact_p"] < 0.5 * theory["stress"]]
    assert pressed[-1] == pytest.approx(theory["t_contact"][1], abs=2 * case.dt)
    assert h["end_uz"].min() > -1e-12  # the face never goes through the wall
    assert h["contact_p"][0] == 0.0  # the initial state, as every solver gives it: the wall acts from then on


@pytest.mark.slow
def test_elastic_thick_cylinder_converges_to_its_exact_in_time_response():
    """The elastic thick cylinder (r1, 2D, lumped): central differences against the modal
    response of the same matrices (all 7936 modes, exact in time, so only the time error is
    left). Measured: 0.19 / 0.36 / 0.14 % at the default half critical step, 0.031 / 0.020 /
    0.011 % at an eighth of it, 0.008 / 0.005 / 0.003 % at a sixteenth: the error falls at
    every halving of the step, at order 2 once asymptotic, and is within 0.05 % at an
    eighth. On the truth's ladders the step shrinks with the mesh (an eighth of r1's at r8),
    so the time error of the finest mesh is within 0.05 % and falls as h^2 with the space error."""
    case = get_case("thick_cylinder", {"refine": 1})
    model = Model(case, lumped=True)
    system = ExplicitSystem(model)
    free, Q = model.free, model.Q[model.free]
    s = 1.0 / np.sqrt(system.m)
    w2, psi = la.eigh((s[:, None] * system.K.toarray()) * s[None, :], overwrite_a=True, driver="evd")
    phi = s[:, None] * psi  # M-orthonormal modes
    rigid = w2 < 1e-9 * w2[-1]  # the free ring's rigid motions (the pressure does not drive them)
    probes = Probes(model)
    u = np.zeros(model.basis.N)
    P = np.empty((len(probes.names), phi.shape[1]))
    for j in range(phi.shape[1]):
        u[free] = phi[:, j]
        P[:, j] = probes.values(u, system)
    coef = P * (phi.T @ Q)
    w2 = np.where(rigid, 1.0, w2)
    t = np.arange(case.n_steps + 1) * case.dt
    exact = (np.where(rigid, 0.0, coef / w2) @ (1.0 - np.cos(np.outer(np.sqrt(w2), t)))
             + np.outer(coef[:, rigid].sum(axis=1), 0.5 * t * t))
    errors = []
    for divisor in (1, 2, 4, 8):
        run = solve(case, step_divisor=divisor)
        errors.append([np.abs(run.history[n] - exact[k]).max() / np.abs(exact[k]).max()
                       for k, n in enumerate(probes.names)])
    errors = np.array(errors)
    assert np.all(errors[1:] < errors[:-1]), errors
    assert np.all(errors[-1] < 5e-4), errors
