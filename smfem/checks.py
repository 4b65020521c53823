"""SMFEM's own numerical checks, for the stability study (reached through the solver table,
``smfem.runs.registry.checks('smfem')``): the static solution's probes, the explicit stability limit,
free vibration far beyond it, and the conditioning of a harmonic's stiffness."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.sparse.linalg as sla

from .layer_law import ContactError
from .model import Model
from .newmark import LinearSystem, State, march
from .options import SolverOptions
from .probes import CaseProbes, ProbeSet
from .stacking import stacked
from .strategy import build_system

#: the time step of a static contact solve, times the case's: inertia far below the stiffness
STATIC_DT_FACTOR = 1e6
#: the static contact solution's iterative refinement: passes at most, and the largest last
#: correction (max-norm, relative to u's) of one that has converged
STATIC_REFINEMENTS = 8
STATIC_REFINED = 1e-10


def static_probes(case, element: str | None = None) -> dict:
    """The static solution under the case's loads (``element``: another than the case's): probe
    name -> value."""
    model = Model(case, element=element)
    K, _, Q, _, _ = stacked(model)
    u = sla.spsolve(K.tocsc(), Q)
    probes = ProbeSet(model, case.probes)
    return dict(zip(probes.names, probes.evaluate(u, u)))


def contact_static_probes(case, options: SolverOptions | None = None) -> dict:
    """The static solution of a case with contact under its held loads: one step of the contact
    system (the layer's states iterated as in any step) with a time step so long that inertia
    is small (``a0 M`` about 1e-11 of ``K``'s diagonal at the rod's sizes) and nothing moving
    before it, then refined to the static balance itself (no inertia): probe name -> value.

    The step alone loses digits where a body floats, held only by the layer (the striker): held
    by ``a0 M`` alone, its rigid motion in ``A0^-1 b`` is ``k1 / (a0 m)`` times the answer (9e6
    on the rod), and the layer's Woodbury solve cancels it, its face system ``I + k S`` as ill
    conditioned (the layer's stiffness over ``a0 m``: 3e11 on the rod): 2e-5 of the load out of balance, a
    different amount on every BLAS. So the step's answer is refined: the static residual
    (``a0 = 0``) solved with the step's matrix and states until the corrections stop shrinking.
    A pass shrinks the error by the solve's relative error plus ``a0 m / k1`` (~1e-7): three
    passes on the rod. What is left is the residual's rounding, ``eps`` times the static
    system's condition, as in a bonded solve (measured on four OpenBLAS kernels: 1e-12 of the
    probes); a last correction above :data:`STATIC_REFINED` of ``u`` is an error."""
    long = dataclasses.replace(case, params={**case.params, "dt": STATIC_DT_FACTOR * case.dt})
    model, system, _ = build_system(long, options or SolverOptions())
    zero = np.zeros(model.n_dof)
    system.initial_acceleration(zero)
    u, _ = system.solve(zero, zero, 1, long.dt)
    states, last = system.states, math.inf
    for passes in range(1, STATIC_REFINEMENTS + 1):
        du = system.correction(states, system.static_residual(u, states, long.dt))
        u = u + du
        size = np.abs(du).max() / np.abs(u).max()
        if size >= 0.5 * last:  # no more contraction: at the residual's rounding
            break
        last = size
    if size > STATIC_REFINED:
        raise ContactError(f"{case.name}: the static contact solution does not refine (last correction {size:.2g} "
                           f"of u after {passes} passes)")
    system.strain = system.layer.strain(u)
    if not system.layer.states_of(system.strain).close_to(states):
        raise ContactError(f"{case.name}: the refined static contact solution changes the layer's states")
    probes = CaseProbes(long, model, system)
    return dict(zip(probes.names, probes.values(State(1, u, zero, zero), system)))


def explicit_limit(case) -> tuple[float, list[float]]:
    """Explicit stability limit ``dt_cr = 2 / omega_max`` of the case's decoupled model, and
    ``omega_max`` (rad/s) of each mode: the largest eigenvalue of ``M^-1 K`` per harmonic."""
    return _explicit_limit(Model(case))


def _explicit_limit(model: Model) -> tuple[float, list[float]]:
    """Massless dofs (a 9-node element's nodes on the axis) follow the rest statically: the
    limit is that of the stiffness condensed onto the dofs with mass."""
    omegas = []
    for s in model.systems:
        K, massive = s.K.toarray(), s.M > 0
        if not massive.all():
            m, z = np.flatnonzero(massive), np.flatnonzero(~massive)
            K = K[np.ix_(m, m)] - K[np.ix_(m, z)] @ np.linalg.solve(K[np.ix_(z, z)], K[np.ix_(z, m)])
        d = 1.0 / np.sqrt(s.M[massive])
        omegas.append(math.sqrt(np.linalg.eigvalsh(K * d[:, None] * d[None, :]).max()))
    return 2.0 / max(omegas), omegas


def free_vibration(case, factors=(1, 10, 100), n_steps: int = 10_000, seed: int = 1) -> list[dict]:
    """Free vibration released from the static deflection under the case's load, with random
    initial velocities of the same energy (every mode excited, the highest included), stepped
    with ``dt = factor * dt_cr``.

    Rows: ``energy_drift`` is max over all steps of |E_n - E_0| / E_0 (E kinetic plus strain);
    ``strain_energy_max`` the largest strain energy over E_0 (bounded: at most 1 + drift);
    ``u_max_ratio`` the largest |u| over the run relative to the initial one.
    """
    model = Model(case)
    K, M, Q, _, _ = stacked(model)
    dt_cr, omegas = _explicit_limit(model)
    u0 = sla.spsolve(K.tocsc(), Q)
    v0 = np.random.default_rng(seed).normal(size=len(Q))
    v0 *= math.sqrt((u0 @ (K @ u0)) / (v0 @ (M * v0)))
    rows = []
    for factor in factors:
        system = LinearSystem(K, M, np.zeros_like(Q), factor * dt_cr)
        e0 = sum(system.energy(u0, v0))
        drift, strain_max, u_max = 0.0, 0.0, np.abs(u0).max()
        for state in march(system, u0, v0, factor * dt_cr, n_steps):
            kinetic, strain = system.energy(state.u, state.v)
            drift = max(drift, abs(kinetic + strain - e0) / e0)
            strain_max = max(strain_max, strain / e0)
            u_max = max(u_max, np.abs(state.u).max())
        rows.append({
            "case": case.name, "modes": len(model.systems), "n_dof": model.n_dof, "omega_max": max(omegas),
            "dt_cr": dt_cr, "factor": factor, "dt": factor * dt_cr, "n_steps": n_steps, "energy_drift": drift,
            "strain_energy_max": strain_max, "u_max_ratio": u_max / np.abs(u0).max(),
            "finite": bool(np.isfinite(state.u).all()),
        })
    return rows


def stiffness_condition(case) -> float:
    """2-norm condition number of the first harmonic's stiffness."""
    return float(np.linalg.cond(Model(case).systems[0].K.toarray()))
