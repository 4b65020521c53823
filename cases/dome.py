"""Clamped spherical cap under suddenly applied external pressure (Bathe, Ramm & Wilson 1975).

Paper's values: geometry, material, load, time window, dt, the 4 x 20 mesh, the published apex
history (read off Bathe's curve) and the 1 % claim. Ours: the coordinate origin at the sphere
centre, the apex probe on the mid-surface.
"""

import math

from .case import Case
from .geometry import RING, Axis, Pressure, Probe, Section, Support
from .material import Material, tau_s_from_sigma_y
from .params import COMMON, MAX_STRESS, Spec

NAME = "dome"
TITLE = "Clamped spherical cap, suddenly applied pressure (axisymmetric)"
R, H, HALF_ANGLE_DEG = 22.27, 0.41, 26.67

DEFAULTS = dict(
    dt=5e-6, t_end=1e-3, refine=1, harmonics=1, E=10.5e6, nu=0.3, rho=2.45e-4,
    tau_s=tau_s_from_sigma_y(24000.0), plastic=False, tol=1e-5, dim=2, q=600.0,
)
SPECS = dict(COMMON, q=Spec(float, -MAX_STRESS, MAX_STRESS, help="external pressure, psi"))
PROVENANCE = dict(
    paper="R, h, half-angle, E, nu, rho, sigma_y = 24000 psi, E_T, q = 600 psi, dt = 5e-6 s, "
    "t_end = 1e-3 s, 4 x 20 mesh, published apex extrema",
    ours="origin at the sphere centre; apex_uz on the mid-surface; tol",
)


def build(p: dict) -> Case:
    alpha = math.radians(HALF_ANGLE_DEG)
    section = Section(
        "polar",
        s=Axis((R - H / 2, R + H / 2), (4,)),
        t=Axis((0.0, alpha), (20,)),
        edges={"inner": "s_min", "outer": "s_max", "axis": "t_min", "clamped": "t_max"},
    )
    return Case(
        name=NAME, title=TITLE, body=RING, section=section,
        material=Material(p["E"], p["nu"], p["rho"], p["tau_s"], E_T=0.21e6, plastic=p["plastic"]),
        loads=(Pressure(p["q"], "outer", ((0.0, 2 * math.pi),)),),
        supports=(Support("clamped", (1, 2, 3)),),
        probes=(Probe("apex_uz", "point", "u", (2,), point=(0.0, R, 0.0)),),
        params=p, axisymmetric=True, units="in, lbf, s (psi, lbf s^2/in^4)",
        provenance=PROVENANCE,
        references={
            "apex_uz_extrema": {
                "source": "Bathe, Ramm & Wilson (1975), elastic apex history read off the curve; "
                "apex_uz = -(inward deflection)",
                "points": [(0.18e-3, -0.051), (0.36e-3, -0.090), (0.58e-3, 0.05)],
                "kinds": ["min", "min", "max"],
            },
            "paper_claim": "within 1 % of the reference with 4 x 20 elements",
        },
    )
