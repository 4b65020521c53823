"""Two coaxial elastic rods colliding: a striker on a target at rest, through the contact layer.

The issue's scene (issue 39): two steel rods of radius 0.05 m, the striker on z in [-0.5, 0]
moving at +5 m/s along z, the target on z in [0, 1] at rest, the faces touching at t = 0 (gap
0), frictionless, free far ends, t_end = 6e-4 s; the layer's thickness and stiffness as
``rod_impact``'s. Ours: the meshes (5 x 50 and 5 x 100 elements, rod_impact's 0.01 m spacing
along z), dt = 1e-6 s as the rod's, tol.

With nu = 0 the rods are one-dimensional and the collision has an exact answer
(:func:`collision_histories`): both faces move at v0 / 2 under the stress -rho c v0 / 2 until the
striker's wave has been to its free end and back (2 L1 / c); then the striker rests, the faces
part and the target carries a compressive pulse 2 L1 long, which its free end reflects as
tension. With nu = 0.3 the pulse rings behind its front (the radial inertia): histories compare
through the window 2R/c (``references['comparison_window_s']``), as the rod's, where it fits
whole (:func:`smfem.runs.errors.inside_window`: at the record's last sample a one-sided window let the
mesh-scale ringing through, and target_mid_szz looked divergent over the explicit ladder).
"""

import math

import numpy as np

from .bodies import Body, assemble
from .case import Case
from .geometry import RING, Axis, ContactPair, InitialVelocity, Probe, Section
from .material import Material
from .params import COMMON, PAIR_SPECS, Spec

NAME = "rod_collision"
TITLE = "Two elastic rods colliding (contact between deformable bodies)"
RADIUS, STRIKER, TARGET = 0.05, 0.5, 1.0

DEFAULTS = dict(
    dt=1e-6, t_end=6e-4, refine=1, harmonics=1, E=2.1e11, nu=0.3, rho=7.8e3, tau_s=1.7e8, plastic=False,
    tol=1e-5, dim=2, v0=5.0, friction=0.0, layer_thickness=1e-4, layer_stiffness=1.0,
)
SPECS = dict(
    COMMON,
    **PAIR_SPECS,
    v0=Spec(float, 0.0, 1e5, open_lo=True, help="the striker's speed towards the target, m/s"),
)
PROVENANCE = dict(
    paper="the contact layer between deformable bodies (17)-(19); the rods' material and layer as the rod impact's",
    ours="the scene (issue 39): striker 0.5 m and target 1 m long, radius 0.05 m, v0 = 5 m/s, gap 0, "
    "frictionless; meshes 5 x 50 and 5 x 100, dt = 1e-6 s, t_end = 6e-4 s",
)


def sections() -> tuple[Body, Body]:
    """The striker and the target: (r, z) blocks with the rod's 0.01 m spacing along z."""
    edges = {"axis": "s_min", "lateral": "s_max"}
    return (Body("striker", Section("rect", Axis((0.0, RADIUS), (5,)), Axis((-STRIKER, 0.0), (50,)),
                                    dict(edges, end="t_min", face="t_max"))),
            Body("target", Section("rect", Axis((0.0, RADIUS), (5,)), Axis((0.0, TARGET), (100,)),
                                   dict(edges, face="t_min", end="t_max"))))


def collision_theory(E: float, rho: float, v0: float) -> dict:
    """The one-dimensional answer's constants (exact for nu = 0): the wave speed, the contact
    stress, the contact time 2 L1 / c, the velocities after it."""
    c = math.sqrt(E / rho)
    return {"c": c, "stress": -0.5 * rho * c * v0, "t_contact": 2 * STRIKER / c,
            "striker_v_after": 0.0, "target_v_after": v0 * STRIKER / TARGET}


def collision_histories(t, E: float, rho: float, v0: float) -> dict[str, np.ndarray]:
    """The five probes of the one-dimensional collision (nu = 0) at times ``t``.

    The contact sends a pulse ``f`` of stress -rho c v0 / 2 and duration T = 2 L1 / c into the
    target; each free-end reflection changes its sign, so at z the stress is the sum of the
    right-going ``f(t - (z + 2 k L2) / c)`` and the left-going ``-f(t - ((2 k + 2) L2 - z) / c)``.
    The far end moves at v0 while a pulse is there; the striker's mean velocity falls linearly
    to 0 over T (its wave runs out and back), the target's rises to L1 / L2 v0 (momentum)."""
    t = np.asarray(t, float)
    th = collision_theory(E, rho, v0)
    c, s, T = th["c"], th["stress"], th["t_contact"]

    def pulse(tau):
        return np.where((tau > 0) & (tau < T), 1.0, 0.0)

    mid = 0.5 * TARGET
    rounds = range(int(t.max(initial=0.0) * c / (2 * TARGET)) + 2)
    mid_stress = s * sum(pulse(t - (mid + 2 * k * TARGET) / c) - pulse(t - ((2 * k + 2) * TARGET - mid) / c)
                         for k in rounds)
    # the end moves at v0 while a pulse is at it: from (2 k + 1) L2 / c for T
    end_uz = v0 * sum(np.clip(t - (2 * k + 1) * TARGET / c, 0.0, T) for k in rounds)
    share = np.clip(t / T, 0.0, 1.0)
    return {"contact_p": s * pulse(t), "target_mid_szz": mid_stress, "striker_vz": v0 * (1 - share),
            "target_vz": th["target_v_after"] * share, "target_end_uz": end_uz}


def pulse_errors(t, history, E: float, rho: float, v0: float, window: float) -> dict[str, float]:
    """The stress pulses of a run (``history['contact_p']``, ``history['target_mid_szz']`` at
    times ``t``) against the one-dimensional answer's (nu = 0), as relative deviations: each
    pulse's level (its mean over the contact, at mid-length over the first pulse's passage, a
    ``window`` in from either end) and its duration (its impulse over the answer's level: the
    contact's over the whole run, the mid-length's up to the end of the first pulse, which the
    reflected tension follows at once). A discrete front is smeared over a few elements, so a
    max-norm across the jump of the stress would judge the smearing, not the pulse."""
    t = np.asarray(t, float)
    th = collision_theory(E, rho, v0)
    s, T = th["stress"], th["t_contact"]
    arrive = 0.5 * TARGET / th["c"]
    out = {}
    for name, start, upto in (("contact_p", 0.0, np.inf), ("target_mid_szz", arrive, arrive + T)):
        x = np.asarray(history[name], float)
        level = x[(t > start + window) & (t < start + T - window)].mean()
        first = t <= upto
        out[f"{name}_level"] = level / s - 1
        out[f"{name}_duration"] = np.trapezoid(x[first], t[first]) / s / T - 1
    return out


def build(p: dict) -> Case:
    section = assemble(sections(), path=NAME)
    probes = (
        Probe("contact_p", "edge_mean", "sigma", ("n", "n"), edge="target.face"),
        Probe("target_mid_szz", "point", "sigma", (2, 2), point=(0.0, 0.5 * TARGET, 0.0)),
        Probe("striker_vz", "body_mean", "v", (2,), region="striker"),
        Probe("target_vz", "body_mean", "v", (2,), region="target"),
        Probe("target_end_uz", "point", "u", (2,), point=(0.0, TARGET, 0.0)),
    )
    return Case(
        name=NAME, title=TITLE, body=RING, section=section,
        material=Material(p["E"], p["nu"], p["rho"], p["tau_s"], plastic=p["plastic"]),
        loads=(), supports=(), probes=probes, params=p,
        initial_velocity=(InitialVelocity(2, p["v0"], region="striker"),),
        contacts=(ContactPair("target.face", "striker.face", p["friction"]),), axisymmetric=True,
        provenance=PROVENANCE,
        references={"collision_theory": collision_theory(p["E"], p["rho"], p["v0"]),
                    "comparison_window_s": 2 * RADIUS / math.sqrt(p["E"] / p["rho"])},
    )
