"""Hinged strip with a notch at mid-span under a suddenly applied uniform pressure (prism).

Paper's values: span, thickness, notch depth and width, steel, tau_s, q, dt, 100 steps,
20 elements through the thickness, probe depths, plastic hinge times. Ours: the number of
Fourier terms (not in the paper; chosen by a convergence study), the element width across the
plane-strain width, contrast 1e-6.
"""

from .case import Case
from .geometry import PRISM, Axis, Cutout, Pressure, Probe, Section, Support
from .material import Material
from .params import COMMON, MAX_STRESS, Spec

NAME = "notched_strip"
TITLE = "Hinged strip with a mid-span notch, uniform pressure (prismatic, plane strain)"
L, H, N_Z = 0.3, 0.1, 20
NOTCH_X3 = (0.145, 0.155)
Z_PEPS_NOTCH, Z_PEPS_TOP = 0.0275, 0.0975  # element centres of the paper's 5 mm rows

DEFAULTS = dict(
    dt=3.2e-6, t_end=3.2e-4, refine=1, harmonics=120, E=2.1e11, nu=0.3, rho=7.8e3, tau_s=1.7e8,
    plastic=True, tol=1e-5, dim=2, q=0.85e8, notch_depth=0.025, contrast=1e-6,
)
SPECS = dict(
    COMMON,
    q=Spec(float, -MAX_STRESS, MAX_STRESS, help="pressure on the top face, Pa"),
    notch_depth=Spec(float, 0.0, Z_PEPS_NOTCH, open_hi=True,
                     help="notch depth, m (0 = no notch; the notch root stays below the peps_notch probe)"),
    contrast=Spec(float, 0.0, 1.0, open_lo=True, help="stiffness and density factor of notch material"),
)
PROVENANCE = dict(
    paper="L, h, notch 25 x 10 mm, steel, tau_s, q = 0.85e8 Pa, dt = 3.2e-6 s, 100 steps, "
    "20 elements through the thickness, probe depths, plastic hinge times",
    ours="harmonics = 120 (paper silent; by convergence against the truth, benchmarks/notched_harmonics.py: "
    "mid_uz 24 / 6.3 / 0.66 / 0.49 / 0.46 % off at 20 / 80 / 120 / 160 / 400 terms, the truth's uncertainty 1.35 %; "
    "peps_top 1.6 % from 400 terms at 120; a 10 mm notch needs many terms), element width across the "
    "plane-strain width, contrast 1e-6, tol",
)


def build(p: dict) -> Case:
    dz = H / N_Z
    section = Section(
        "rect", s=Axis((0.0, dz), (1,), refinable=False), t=Axis((0.0, H), (N_Z,)),
        edges={"bottom": "t_min", "top": "t_max"},
    )
    probes = [Probe("mid_uz", "point", "u", (2,), point=(0.0, H, L / 2))]
    if p["plastic"]:
        probes += [
            Probe("peps_notch", "point", "peps", point=(dz / 2, Z_PEPS_NOTCH, L / 2)),
            Probe("peps_top", "point", "peps", point=(dz / 2, Z_PEPS_TOP, L / 2)),
        ]
    d = p["notch_depth"]
    return Case(
        name=NAME, title=TITLE, body=PRISM, section=section, length=L,
        material=Material(p["E"], p["nu"], p["rho"], p["tau_s"], plastic=p["plastic"]),
        loads=(Pressure(p["q"], "top", ((0.0, L),)),),
        supports=(Support("all", (1,)),),
        probes=tuple(probes), params=p,
        cutouts=(Cutout((0.0, dz), (0.0, d), (NOTCH_X3,)),) if d > 0 else (),
        contrast=p["contrast"], provenance=PROVENANCE,
        references={
            "plastic_zone_times": (0.96e-4, 3.2e-4),  # the plastic hinge forming
            # measured: benchmarks/notched_convergence.py (the 2D reference at refine 1 ... 4)
            "singular_probes": {
                "peps_notch": "in the plastic hinge 2.5 mm above the notch root, where ideal plasticity past the "
                              "collapse load strains in mesh-size bands from the notch corners: the reference's own "
                              "peak goes 0.29, 0.28, 0.18, 0.08 from refine 1 to 4",
                "peps_top": "in the same hinge at the loaded face: the reference's own peak goes 0.067, 0.072, "
                            "0.060, 0.052 from refine 1 to 4, without converging",
            },
        },
    )
