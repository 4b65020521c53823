"""The paper's hinged strip under a pressure patch moving along its span (prism): a load that
varies in space and time, as a wheel on a rail or a bridge.

The issue's values: the notched strip's span L = 0.3 m, thickness h = 0.1 m, steel (E = 2.1e11
Pa, nu = 0.3, rho = 7800 kg/m^3), elastic, unnotched by default (``notch_depth`` as the notched
strip's); a pressure q = 1e6 Pa (compression positive) on a patch 0.03 m long across the top
face, moving from x3 = 0 towards x3 = L at 1000 m/s: at time t it covers
[1000 t - 0.03, 1000 t] within [0, L] (it enters the strip over the first 3e-5 s and leaves it
at 3.3e-4 s); t_end = 6e-4 s; probes ``mid_uz`` (u_2 on the top face at mid-span) and ``q_uz``
(at x3 = L / 4).
Ours: dt and the number of Fourier terms (measured against the exact answer: ``PROVENANCE``),
the plastic load q = 1e8 Pa (the notch's corners yield as the patch passes, peps_max 0.8 % at
refine 2; at 2e8 the ligament collapses, strains reach 9 % at refine 4, past the small-strain
model's 5 %), the notch's material contrast 1e-6 as the notched strip's.
"""

from dataclasses import replace

from . import notched_strip
from .case import Case
from .geometry import PRISM, Axis, Cutout, Pressure, Probe, Section, Support
from .material import Material
from .notched_strip import H, L, N_Z, NOTCH_X3
from .params import COMMON, MAX_STRESS, Spec

NAME = "moving_load"
TITLE = "Hinged strip under a pressure patch moving along the span at 1000 m/s (prismatic, plane strain)"
#: the scene with a notch (``notch_depth > 0``): a case of its own name (cases.VARIANTS holds the
#: issue's, 25 mm deep and plastic)
NOTCHED_NAME = "moving_load_notched"
NOTCHED = {"notch_depth": 0.025, "plastic": True}
PATCH, SPEED = 0.03, 1000.0
Q_ELASTIC, Q_PLASTIC = 1.0e6, 1.0e8
#: Fourier terms: the smooth patch's, and with a notch (a 25 mm cut-out of contrast 1e-6 is a
#: step in the stiffness along the span: the notched strip's 120; at 60 the elastic notched
#: scene's deflections are 27 % from the explicit 2D reference at refine 2, at 120 2.2 %)
HARMONICS, HARMONICS_NOTCHED = 60, 120

DEFAULTS = dict(
    dt=2e-6, t_end=6e-4, refine=1, harmonics=None, E=2.1e11, nu=0.3, rho=7.8e3, tau_s=1.7e8,
    plastic=False, tol=1e-5, dim=2, q=None, notch_depth=0.0, contrast=1e-6, speed=SPEED,
)
SPECS = dict(
    COMMON,
    harmonics=replace(COMMON["harmonics"], help=f"number of Fourier terms kept (default {HARMONICS}, "
                                                f"{HARMONICS_NOTCHED} with a notch)"),
    q=Spec(float, -MAX_STRESS, MAX_STRESS, help="patch pressure, Pa (default 1e6 elastic, 1e8 plastic)"),
    # the notched strip's notch, its bounds shared
    notch_depth=replace(notched_strip.SPECS["notch_depth"], help="notch depth at mid-span, m (0 = no notch, the default)"),
    contrast=notched_strip.SPECS["contrast"],
    speed=Spec(float, 1e-3, 1e5, help="the patch's speed along the span, m/s"),
)
PROVENANCE = dict(
    issue="L, h, steel, elastic, q = 1e6 Pa, the 0.03 m patch from x3 = 0 at 1000 m/s, t_end = 6e-4 s, "
    "probes mid_uz and q_uz, notch_depth as the notched strip's",
    ours="dt = 2e-6 s and 60 Fourier terms (total error 0.24 / 0.35 % on mid_uz / q_uz against the exact answer "
    "of tests/test_truth_timed.py; 120 terms at dt / 2: 0.17 / 0.16 %; benchmarks/moving_load_settings.py against "
    "the stored truth), the plastic load 1e8 Pa (valid: at 2e8 strains pass 5 %), contrast 1e-6, element width across the plane-strain width, tol",
)


def build(p: dict) -> Case:
    notched = p["notch_depth"] > 0
    p = dict(p, q=p["q"] if p["q"] is not None else (Q_PLASTIC if p["plastic"] else Q_ELASTIC),
             harmonics=p["harmonics"] or (HARMONICS_NOTCHED if notched else HARMONICS))
    dz = H / N_Z
    section = Section(
        "rect", s=Axis((0.0, dz), (1,), refinable=False), t=Axis((0.0, H), (N_Z,)),
        edges={"bottom": "t_min", "top": "t_max"},
    )
    probes = [Probe("mid_uz", "point", "u", (2,), point=(0.0, H, L / 2)),
              Probe("q_uz", "point", "u", (2,), point=(0.0, H, L / 4))]
    if p["plastic"]:
        probes.append(Probe("peps_max", "max", "peps"))
    d = p["notch_depth"]
    references = {}
    if p["plastic"] and d > 0:
        references["singular_probes"] = {
            "peps_max": "the largest plastic strain is at the notch's re-entrant corners, where ideal plasticity "
                        "strains in mesh-size bands (the notched strip's peps probes: no converged peak)"}
    return Case(
        name=NOTCHED_NAME if d > 0 else NAME, title=TITLE + (f", a {1000 * d:g} mm notch" if d > 0 else ""),
        body=PRISM, section=section, length=L, references=references,
        material=Material(p["E"], p["nu"], p["rho"], p["tau_s"], plastic=p["plastic"]),
        loads=(Pressure(p["q"], "top", ((-PATCH, 0.0),), speed=p["speed"]),),
        supports=(Support("all", (1,)),),
        probes=tuple(probes), params=p,
        cutouts=(Cutout((0.0, dz), (0.0, d), (NOTCH_X3,)),) if d > 0 else (),
        contrast=p["contrast"], provenance=PROVENANCE,
    )
