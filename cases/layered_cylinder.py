"""A bonded two-material thick cylinder under the thick cylinder's two pressure patches
(plane strain): the section's *structure*, several materials in one body.

The issue's values (its scene, not the paper's): inner layer r in [1.0, 1.4] m of steel
(E = 2.1e11 Pa, nu = 0.3, rho = 7800 kg/m^3, tau_s = 1.7e8 Pa), outer layer r in [1.4, 2.0] m of
aluminium (E = 7.0e10 Pa, nu = 0.33, rho = 2700 kg/m^3, tau_s = 0.9e8 Pa), bonded; pressure q
(compression positive) on the outer surface over |theta| <= 45 deg and |theta - 180 deg| <= 45 deg,
held from t = 0 (or, with ``load = pulse``, through the amplitude (0, 0), (2e-4 s, 1), (6e-4 s, 0), zero
after); elastic q = 1 Pa; dt = 4e-5 s, t_end = 4e-3 s, 8 + 12 elements through the two
layers, 20 harmonics; probes A, B, C as the thick cylinder's and I on the interface.
Ours: the plastic load q = 5e7 Pa (the thick cylinder's), which yields both layers (peps up to
about 0.6 % in each by t_end: tests/test_layered.py), and the axial element length (one
element, as long as a radial one of the inner layer).
"""


from .case import Case
from .geometry import RING, Amplitude, Axis, Pressure, Probe, Region, Section, Support
from .material import Material
from .params import COMMON, MAX_STRESS, MIN_MODULUS, Spec
from .thick_cylinder import PATCHES, patch_probes

NAME = "layered_cylinder"
TITLE = "Bonded steel-aluminium cylinder, pressure on two opposite 90 deg patches (plane strain)"
#: the scene with ``load = pulse``: a case of its own name (cases.VARIANTS)
PULSE_NAME = "layered_cylinder_pulse"
R1, R_I, R2 = 1.0, 1.4, 2.0
N_INNER, N_OUTER = 8, 12
Q_ELASTIC, Q_PLASTIC = 1.0, 5.0e7

DEFAULTS = dict(
    dt=4e-5, t_end=4e-3, refine=1, harmonics=20, E=2.1e11, nu=0.3, rho=7.8e3, tau_s=1.7e8,
    E_outer=7.0e10, nu_outer=0.33, rho_outer=2.7e3, tau_s_outer=0.9e8,
    plastic=False, tol=1e-5, dim=2, q=None,
)
SPECS = dict(
    COMMON,
    q=Spec(float, -MAX_STRESS, MAX_STRESS, help="patch pressure, Pa (default 1 elastic, 5e7 plastic)"),
    E_outer=Spec(float, MIN_MODULUS, MAX_STRESS, help="outer layer's Young's modulus, Pa (E, nu, rho, tau_s: the inner's)"),
    nu_outer=COMMON["nu"], rho_outer=COMMON["rho"], tau_s_outer=COMMON["tau_s"],
    # absent from DEFAULTS (a step when not set), so the stored truth of the step keeps its key
    load=Spec(str, choices=("step", "pulse"),
              help="the patches' history: a step held from t = 0 (the default) or the pulse 0 -> 1 at 2e-4 s -> 0 "
                   "at 6e-4 s"),
)
#: the pulse of ``load = pulse`` (the issue's): up over 0.2 ms, down by 0.6 ms, zero after
PULSE = Amplitude(((0.0, 0.0), (2e-4, 1.0), (6e-4, 0.0)))
PROVENANCE = dict(
    issue="the two layers' radii and materials, the 45 deg patches, q = 1 Pa, dt = 4e-5 s, t_end = 4e-3 s, "
    "8 + 12 elements, 20 Fourier terms, probes A, B, C, I; load = pulse and its amplitude",
    ours="plastic q = 5e7 Pa, axial element length, tol",
)


def build(p: dict) -> Case:
    p = dict(p, q=p["q"] if p["q"] is not None else (Q_PLASTIC if p["plastic"] else Q_ELASTIC))
    dz = (R_I - R1) / N_INNER
    section = Section(
        "rect", s=Axis((R1, R_I, R2), (N_INNER, N_OUTER)), t=Axis((0.0, dz), (1,), refinable=False),
        edges={"inner": "s_min", "outer": "s_max"},
    )
    outer = Material(p["E_outer"], p["nu_outer"], p["rho_outer"], p["tau_s_outer"], plastic=p["plastic"])
    probes = patch_probes(R1, R2) + [Probe("I_ur", "point", "u", (1,), point=(R_I, 0.0, 0.0))]
    if p["plastic"]:
        probes.append(Probe("peps_max", "max", "peps"))
    pulse = p.get("load") == "pulse"
    return Case(
        name=PULSE_NAME if pulse else NAME, title=TITLE + (", a pulse" if pulse else ""), body=RING, section=section,
        material=Material(p["E"], p["nu"], p["rho"], p["tau_s"], plastic=p["plastic"]),
        regions=(Region("outer", outer, s_range=(R_I, R2), t_range=(0.0, dz)),),
        loads=(Pressure(p["q"], "outer", PATCHES, amplitude=PULSE if pulse else None),),
        supports=(Support("all", (2,)),),
        probes=tuple(probes), params=p, provenance=PROVENANCE,
    )
