"""SMFEM run of a scene with a rigid wall: the contact layer stepped with Newmark.

Probes: point probes as in any linear run; ``edge_mean`` of the normal stress on the struck
face is the layer's mean normal stress (the contact pressure itself); ``body_mean`` of the
velocity is the mass-weighted mean (momentum / mass).
"""

from __future__ import annotations

import time

import numpy as np

from .contact import ContactError, ContactLayer, ContactNewmark
from .fields import field_mesh
from .model import ModelError
from .probes import ProbeSet
from .result import RunResult

#: relative energy gain over a run without loads beyond which the result is rejected
ENERGY_GAIN_LIMIT = 0.01


def _energy(stepper, layer, u, v, strain, state) -> float:
    """Kinetic + strain energy of the rod and the layer (per radian: the model's integrals)."""
    rod = 0.5 * v @ (stepper.M * v) + 0.5 * u @ (stepper.K @ u)
    sigma = layer.stress(strain, state)
    total_strain = strain + layer.offset_strain(state)
    return float(rod + 0.5 * np.einsum("er,er,e->", sigma, total_strain, layer.ops.sqrt_g))


def solve_contact(case, model, progress=None, with_fields=False, cpu0=None, massless_face=True) -> RunResult:
    cpu0 = time.process_time() if cpu0 is None else cpu0
    p = case.params
    layer = ContactLayer(model, p["layer_thickness"], p["layer_stiffness"] * case.material.E)
    stepper = ContactNewmark(model, layer, case.dt, massless_face)
    linear = [q for q in case.probes if q.kind == "point"]
    probes = ProbeSet(model, linear)
    T = model.systems[0].T
    m_full = stepper.m_full
    axial = np.zeros_like(m_full)
    axial[1::3] = m_full[1::3]  # x2 = z is the axis of the rod
    velocity_row = (T.T @ axial) / axial.sum()
    for q in case.probes:
        if q.kind != "point" and (q.kind, q.field) not in (("edge_mean", "sigma"), ("body_mean", "v")):
            raise ModelError(f"{case.name}: probe {q.name!r} ({q.kind} of {q.field}) is not available with contact")
    names = list(case.probe_names)
    n = case.n_steps
    values = np.full((n + 1, len(names)), np.nan)
    u = np.zeros(T.shape[1])
    v = model.systems[0].V0.copy()
    a = stepper.initial_acceleration(u)
    strain, state = layer.centre_strain(T @ u), layer.state

    def record(k):
        point = dict(zip(probes.names, probes.evaluate(u, v)))
        for j, q in enumerate(case.probes):
            if q.kind == "point":
                values[k, j] = point[q.name]
            elif q.kind == "edge_mean" and q.field == "sigma":
                values[k, j] = layer.mean_normal_stress(strain, state)
            elif q.kind == "body_mean" and q.field == "v":
                values[k, j] = velocity_row @ v

    record(0)
    energy_before = _energy(stepper, layer, u, v, strain, state)
    iterations, message, contact_steps = [], "", []
    for k in range(1, n + 1):
        try:
            u, v, a, its, strain, state = stepper.step(u, v, a, k, k * case.dt)
        except ContactError as exc:
            message = str(exc)
            break
        iterations.append(its)
        if (state != 0).any():
            contact_steps.append(k)
        record(k)
        if progress:
            progress(k, n)
    energy_after = _energy(stepper, layer, u, v, strain, state)
    gain = energy_after / energy_before - 1 if energy_before > 0 else 0.0
    if not message and not case.loads and gain > ENERGY_GAIN_LIMIT:
        # nothing does work on the rod: energy can only stay or be dissipated by friction
        message = (f"contact created energy: +{gain:.1%} over the run (a layer too stiff for dt chatters "
                   f"unseen between steps): lower layer_stiffness or dt")
    done = len(iterations) + 1
    its = np.array(iterations or [0])
    window = [contact_steps[0] * case.dt, contact_steps[-1] * case.dt] if contact_steps else None
    return RunResult(
        t=np.arange(done) * case.dt, history={name: values[:done, j] for j, name in enumerate(names)},
        n_dof=model.n_dof, iterations=iterations, converged=not message, message=message,
        cpu_time_s=time.process_time() - cpu0,
        mesh=field_mesh(model, [u]) if with_fields else None,
        info={"harmonics_used": model.harmonics_used(), "factorizations": stepper.factorizations,
              "n_elements": model.mesh.n_elements, "layer_elements": len(layer.state),
              "solve": "contact layer (17)-(19): states iterated per step, factorizations cached by state",
              "iterations_mean": float(its.mean()), "iterations_max": int(its.max()),
              "energy_before": energy_before,
              "energy_after": energy_after,
              "contact_window": window, "max_layer_compression": stepper.max_closure},
    )
