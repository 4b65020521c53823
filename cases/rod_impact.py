"""Elastic rod striking a rigid wall (axisymmetric contact; a tilted wall makes it 3-D).

Paper's values: the scene (rod on a rigid wall through a thin contact layer, f = 0), steel.
Ours: length, radius, v0, the mesh (5 x 100), dt, t_end, the plastic variant's tau_s, and the
``wall_slope`` variant: the wall tilted by ``atan(wall_slope)`` about a diameter of the face,
so that the rod strikes it first at theta = 0 on the face's rim and the contact zone spreads
over the face (open and closed parts around the circumference: the contact is not
axisymmetric). It needs ``harmonics`` > 1 in SMFEM and ``dim=3`` in the reference FEM.
"""

import math

from .case import Case
from .geometry import RING, Axis, InitialVelocity, Probe, Section, Wall
from .material import Material
from .params import COMMON, Spec

NAME = "rod_impact"
TITLE = "Elastic rod striking a rigid wall (axisymmetric contact)"
LENGTH, RADIUS = 1.0, 0.05

DEFAULTS = dict(
    dt=1e-6, t_end=6e-4, refine=1, harmonics=1, E=2.1e11, nu=0.3, rho=7.8e3, tau_s=1.7e8,
    plastic=False, tol=1e-5, dim=2, v0=5.0, gap=0.0, friction=0.0, layer_thickness=1e-4, layer_stiffness=1.0,
    wall_slope=0.0,
)
SPECS = dict(
    COMMON,
    v0=Spec(float, 0.0, 1e5, open_lo=True, help="impact speed towards the wall, m/s"),
    gap=Spec(float, 0.0, 0.1, help="initial gap between the struck face and the wall, m"),
    friction=Spec(float, 0.0, 10.0, help="Coulomb friction coefficient"),
    layer_thickness=Spec(float, 1e-9, 1e-2, help="SMFEM contact layer thickness, m"),
    layer_stiffness=Spec(float, 1e-3, 1e6, help="SMFEM contact layer Young's modulus, multiple of E"),
    wall_slope=Spec(float, 0.0, 0.05, help="tilt of the wall across the face (tan of the angle): the gap "
                    "grows by wall_slope per m away from the first-struck rim point; > 0 is not axisymmetric"),
)
PROVENANCE = dict(
    paper="rod on a rigid wall through a thin contact layer, frictionless, steel",
    ours="L = 1 m, radius 0.05 m, v0 = 5 m/s, mesh 5 x 100, dt = 1e-6 s, t_end = 6e-4 s, tol; "
    "the contact layer: thickness 1e-4 m, Young's modulus E",
)


def rod_theory(E: float, rho: float, v0: float, length: float = LENGTH, gap: float = 0.0) -> dict:
    """1-D elastic rod theory (exact for nu = 0): wave speed, stress, contact window."""
    c = math.sqrt(E / rho)
    t0 = gap / v0
    return {
        "c": c,
        "stress": -rho * c * v0,
        "t_contact": (t0, t0 + 2 * length / c),
        "t_mid_stress": (t0 + length / (2 * c), t0 + 3 * length / (2 * c)),
        "rebound_velocity": v0,
    }


def build(p: dict) -> Case:
    section = Section(
        "rect", s=Axis((0.0, RADIUS), (5,)), t=Axis((0.0, LENGTH), (100,)),
        edges={"axis": "s_min", "lateral": "s_max", "face": "t_min", "free_end": "t_max"},
    )
    probes = (
        Probe("mid_szz", "point", "sigma", (2, 2), point=(0.0, LENGTH / 2, 0.0)),
        Probe("contact_p", "edge_mean", "sigma", ("n", "n"), edge="face"),
        Probe("end_uz", "point", "u", (2,), point=(0.0, 0.0, 0.0)),
        Probe("rod_vz", "body_mean", "v", (2,)),
    )
    if p["wall_slope"] > 0:  # the face rim where the tilted wall strikes first, and opposite
        probes += (Probe("rim_uz_0", "point", "u", (2,), point=(RADIUS, 0.0, 0.0)),
                   Probe("rim_uz_180", "point", "u", (2,), point=(RADIUS, 0.0, math.pi)))
    return Case(
        name=NAME, title=TITLE, body=RING, section=section,
        material=Material(p["E"], p["nu"], p["rho"], p["tau_s"], plastic=p["plastic"]),
        loads=(), supports=(), probes=probes, params=p,
        initial_velocity=(InitialVelocity(2, -p["v0"]),),
        wall=Wall("face", p["gap"], p["friction"], p["wall_slope"]), axisymmetric=p["wall_slope"] == 0.0,
        provenance=PROVENANCE,
        references={"rod_theory": rod_theory(p["E"], p["rho"], p["v0"], gap=p["gap"]),
                    # features shorter than a wave's transit of the diameter are mesh-dependent in
                    # every model (the ringing behind the front): histories compare through it
                    "comparison_window_s": 2 * RADIUS / math.sqrt(p["E"] / p["rho"])},
    )
