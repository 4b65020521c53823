"""SMFEM run of a scene with a rigid wall: the contact layer stepped with Newmark.

Probes: point probes as in any linear run; ``edge_mean`` of the normal stress on the struck
face is the layer's mean normal stress (the contact pressure itself); ``body_mean`` of the
velocity is the mass-weighted mean (momentum / mass).
"""

from __future__ import annotations

import time

import numpy as np

from cases.result import RunResult

from .contact import ContactError, ContactLayer, ContactNewmark
from .fields import field_mesh
from .fourier import Mode
from .model import Model, ModelError
from .probes import ProbeSet

#: relative energy gain over a run without loads beyond which the result is rejected
ENERGY_GAIN_LIMIT = 0.01


def contact_model(case) -> Model:
    """The model of a contact run: harmonic 0 alone for an axisymmetric scene, else every mode
    the symmetry of the wall allows (the layer's states couple them)."""
    return Model(case) if case.axisymmetric else Model(case, nonlinear=True)


def _energy(stepper, layer, u, v, strain, states) -> float:
    """Kinetic + strain energy of the body and the layer (the model's integrals over x3)."""
    body = 0.5 * v @ (stepper.M * v) + 0.5 * u @ stepper.stiffness_product(u)
    return float(body + layer.energy(strain, states))


def _mean_axial_velocity_row(model, stepper) -> np.ndarray:
    """Row giving the mass-weighted mean axial velocity (momentum / mass) of stacked amplitudes:
    only harmonic 0 carries a mean."""
    row = np.zeros(model.n_dof)
    for i, (s, m_full) in enumerate(zip(model.systems, stepper.m_full)):
        if s.mode == Mode(0, "c"):
            axial = np.zeros_like(m_full)
            axial[1::3] = m_full[1::3]  # x2 = z is the axis of the rod
            row[stepper.offsets[i]:stepper.offsets[i + 1]] = (s.T.T @ axial) / axial.sum()
    return row


def solve_contact(case, model, progress=None, with_fields=False, cpu0=None, massless_face=True) -> RunResult:
    cpu0 = time.process_time() if cpu0 is None else cpu0
    p = case.params
    layer = ContactLayer(model, p["layer_thickness"], p["layer_stiffness"] * case.material.E)
    stepper = ContactNewmark(model, layer, case.dt, massless_face)
    linear = [q for q in case.probes if q.kind == "point"]
    probes = ProbeSet(model, linear)
    velocity_row = _mean_axial_velocity_row(model, stepper)
    for q in case.probes:
        if q.kind != "point" and (q.kind, q.field) not in (("edge_mean", "sigma"), ("body_mean", "v")):
            raise ModelError(f"{case.name}: probe {q.name!r} ({q.kind} of {q.field}) is not available with contact")
    names = list(case.probe_names)
    n = case.n_steps
    values = np.full((n + 1, len(names)), np.nan)
    u = np.zeros(model.n_dof)
    v = np.concatenate([s.V0 for s in model.systems])
    a = stepper.initial_acceleration(u)
    strain, states = layer.strain(u), layer.states

    def record(k):
        point = dict(zip(probes.names, probes.evaluate(u, v)))
        for j, q in enumerate(case.probes):
            if q.kind == "point":
                values[k, j] = point[q.name]
            elif q.kind == "edge_mean" and q.field == "sigma":
                values[k, j] = layer.mean_normal_stress(strain, states)
            elif q.kind == "body_mean" and q.field == "v":
                values[k, j] = velocity_row @ v

    record(0)
    energy_before = _energy(stepper, layer, u, v, strain, states)
    iterations, message, contact_steps, closed = [], "", [], [0.0]
    for k in range(1, n + 1):
        try:
            u, v, a, its, strain, states = stepper.step(u, v, a, k, k * case.dt)
        except ContactError as exc:
            message = str(exc)
            break
        iterations.append(its)
        closed.append(layer.closed_fraction(states))
        if closed[-1] > 0:
            contact_steps.append(k)
        record(k)
        if progress:
            progress(k, n)
    energy_after = _energy(stepper, layer, u, v, strain, states)
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
        mesh=field_mesh(model, stepper.blocks(u)) if with_fields else None,
        info={"harmonics_used": model.harmonics_used(), "factorizations": stepper.factorizations,
              "n_elements": model.mesh.n_elements, "layer_elements": layer.n_elements,
              "layer_points_x3": int(layer.states.kind.shape[1]),
              "solve": "contact layer (17)-(19): states per layer Gauss point and point along x3, iterated per "
                       "step; one factorization per mode, the layer's face matrix by Woodbury",
              "iterations_mean": float(its.mean()), "iterations_max": int(its.max()),
              "energy_before": energy_before,
              "energy_after": energy_after,
              "contact_window": window, "max_layer_compression": stepper.max_closure,
              "closed_fraction": closed},
    )
