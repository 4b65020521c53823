"""A flywheel (hub, thin web, rim, filleted) struck by a pressure patch on the rim: a section of
*any shape*, meshed by gmsh into unstructured quadrilaterals.

The issue's values: the section (hub r in [0.05, 0.10], z in [-0.04, 0.04]; web r in [0.10, 0.25],
z in [-0.01, 0.01]; rim r in [0.25, 0.30], z in [-0.03, 0.03]; fillets of radius 0.01 m), steel
(E = 2.1e11 Pa, nu = 0.3, rho = 7800 kg/m^3, tau_s = 1.7e8 Pa, ideal plasticity), the bore clamped,
the pressure q on the rim's top face over |theta| <= ``patch_deg`` held from t = 0 (q = 1e6 Pa),
dt = 1e-5 s, t_end = 5e-3 s, about four elements through the web, probes u_z at the rim's outer
top corner at 0, 90 and 180 deg.
Ours: the mesh (``cases/sections/flywheel.py``, kept as ``flywheel.msh``: 808 quad9 elements,
size 5 mm, 2.5 mm on the fillets; SMFEM's 4-node element uses their corners), the plastic
load q = 1.5e7 Pa (``Q_PLASTIC``: the web yields at the hub's fillets, top and bottom, in
bending, equivalent plastic strain about 1.2 % there by 1 ms, the rim 3.8 mm down), and the
harmonics (``HARMONICS``, from the convergence study in docs/scenes.md).
"""

import math
from functools import cache
from pathlib import Path

from .case import Case
from .geometry import RING, Pressure, Probe, Support
from .material import Material
from .params import COMMON, MAX_STRESS, Spec

NAME = "flywheel"
TITLE = "Flywheel (hub, web, rim; gmsh section), pressure patch on the rim"
MESH = Path(__file__).parent / "sections" / "flywheel.msh"
R_RIM, Z_TOP = 0.30, 0.03
Q_ELASTIC, Q_PLASTIC = 1.0e6, 1.5e7
HARMONICS = 24

DEFAULTS = dict(
    dt=1e-5, t_end=5e-3, refine=1, harmonics=HARMONICS, E=2.1e11, nu=0.3, rho=7.8e3, tau_s=1.7e8,
    plastic=False, tol=1e-5, dim=3, q=None, patch_deg=15.0,
)
SPECS = dict(
    COMMON,
    q=Spec(float, -MAX_STRESS, MAX_STRESS, help="pressure on the rim patch, Pa (default 1e6 elastic, 1.5e7 plastic)"),
    patch_deg=Spec(float, 0.0, 180.0, open_lo=True, help="the patch covers |theta| <= patch_deg on the rim's top "
                   "face, deg (180: all round, axisymmetric)"),
)
PROVENANCE = dict(
    issue="section, steel, clamped bore, patch on the rim's top face, q = 1e6 Pa, dt = 1e-5 s, t_end = 5e-3 s, "
    "about four elements through the web, probes rim_uz_0/90/180",
    ours="the gmsh mesh (cases/sections/flywheel.msh), plastic q = 1.5e7 Pa (yields at the hub fillets), harmonics, tol",
)


@cache
def section():
    """The kept mesh, read once (:func:`cases.msh_section.read_msh`)."""
    from .msh_section import read_msh

    return read_msh(MESH, RING)


def build(p: dict) -> Case:
    p = dict(p, q=p["q"] if p["q"] is not None else (Q_PLASTIC if p["plastic"] else Q_ELASTIC))
    half = math.radians(p["patch_deg"])
    axisymmetric = p["patch_deg"] == 180.0
    probes = tuple(Probe(f"rim_uz_{deg}", "point", "u", (2,), point=(R_RIM, Z_TOP, math.radians(deg)))
                   for deg in (0, 90, 180))
    if p["plastic"]:
        probes += (Probe("peps_max", "max", "peps"),)
    return Case(
        name=NAME, title=TITLE, body=RING, section=section(),
        material=Material(p["E"], p["nu"], p["rho"], p["tau_s"], plastic=p["plastic"]),
        loads=(Pressure(p["q"], "rim_top", ((0.0, 2 * math.pi),) if axisymmetric else ((-half, half),)),),
        supports=(Support("bore", (1, 2, 3)),),
        probes=probes, params=p, provenance=PROVENANCE, axisymmetric=axisymmetric,
    )
