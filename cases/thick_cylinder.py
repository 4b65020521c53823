"""Infinite thick-walled cylinder under pressure on two opposite patches (plane strain).

Paper's values: r1, r2, E, nu = 0, rho, tau_s, ideal plasticity, the 45 deg patches, q = 1 Pa,
dt, 15 elements through the wall, 20 Fourier terms, probe points A, B, C, the plastic zone times
and iteration counts. Ours: the plastic load q = 5e7 Pa, t_end = 4e-3 s, the peps_A radius as
printed (1.0333 m), the axial element length (one element, as long as a radial one).
"""

import math

from .case import Case
from .geometry import RING, Axis, Pressure, Probe, Section, Support
from .material import Material
from .params import COMMON, MAX_STRESS, Spec

NAME = "thick_cylinder"
TITLE = "Thick cylinder, pressure on two opposite 90 deg patches (plane strain)"
R1, R2, N_R = 1.0, 2.0, 15
Q_ELASTIC, Q_PLASTIC = 1.0, 5.0e7
PATCHES = ((-math.pi / 4, math.pi / 4), (3 * math.pi / 4, 5 * math.pi / 4))

DEFAULTS = dict(
    dt=4e-5, t_end=4e-3, refine=1, harmonics=20, E=2.1e11, nu=0.0, rho=7.8e3, tau_s=1.7e8,
    plastic=False, tol=1e-5, dim=2, q=None,
)
SPECS = dict(COMMON, q=Spec(float, -MAX_STRESS, MAX_STRESS, help="patch pressure, Pa (default 1 elastic, 5e7 plastic)"))
PROVENANCE = dict(
    paper="r1, r2, E, nu, rho, tau_s, 45 deg patches, q = 1 Pa, dt = 4e-5 s, 15 elements, "
    "20 Fourier terms, probes A, B, C, plastic zone times",
    ours="plastic q = 5e7 Pa, t_end = 4e-3 s, axial element length, tol",
)


def patch_probes(r_inner: float, r_outer: float) -> list[Probe]:
    """Probes A, B, C of a cylinder under the two patches (the layered cylinder's too)."""
    return [
        Probe("A_ur", "point", "u", (1,), point=(r_outer, 0.0, 0.0)),
        Probe("B_ut", "point", "u", (3,), point=(r_outer, 0.0, math.pi / 4)),
        Probe("C_ur", "point", "u", (1,), point=(r_inner, 0.0, math.pi / 2)),
    ]


def build(p: dict) -> Case:
    p = dict(p, q=p["q"] if p["q"] is not None else (Q_PLASTIC if p["plastic"] else Q_ELASTIC))
    dz = (R2 - R1) / N_R
    section = Section(
        "rect", s=Axis((R1, R2), (N_R,)), t=Axis((0.0, dz), (1,), refinable=False),
        edges={"inner": "s_min", "outer": "s_max"},
    )
    probes = patch_probes(R1, R2)
    if p["plastic"]:
        probes += [
            Probe("peps_A", "point", "peps", point=(1.0333, dz / 2, 0.0)),
            Probe("peps_max", "max", "peps"),
        ]
    return Case(
        name=NAME, title=TITLE, body=RING, section=section,
        material=Material(p["E"], p["nu"], p["rho"], p["tau_s"], plastic=p["plastic"]),
        loads=(Pressure(p["q"], "outer", PATCHES),),
        supports=(Support("all", (2,)),),
        probes=tuple(probes), params=p, provenance=PROVENANCE,
        references={
            "paper_claim": "20 Fourier terms converged; FEM needed 60 elements around to come within 1 %",
            "plastic_zone_times": (1.4e-3, 2.28e-3, 3.2e-3),
            "iterations": {"tol=1e-5": 5, "tol=1e-10": 17},
        },
    )
