"""The manufactured scenes of code verification: a ring and a prism whose exact motion is known.

Each is a square cross-section fixed on its four edges (a prism's ends hinged, as every prism
here), driven by the body force that makes a chosen smooth motion exact
(:mod:`cases.manufactured`): a section bubble that vanishes on the edges (a quadratic bubble
times an exponential, in no element's space), times several
harmonics along x3, times ``1 - cos(omega t)`` (at rest at t = 0, so no initial conditions are
needed), or with ``time = "quadratic"`` times ``t^2``: Newmark's scheme integrates a quadratic
exactly, so the step leaves only the mesh's own error (a space ladder can take a long step). With ``free_top`` the top edge is free instead, loaded by the exact traction
``sigma(U) n`` (the bubble neither zero nor flat there). The material may vary smoothly along x3 (``a``: E and rho times ``1 + a cos(2 k x3)``),
which couples the harmonics. Dimensionless units: E = rho = 1, so waves run at about 1.

Both solvers run these as any scene; :func:`exact` gives the probes' exact histories, and the
case carries its motion (``Case.exact``), against which each solver measures its own L2 error.
"""

from __future__ import annotations

import math

import numpy as np
import sympy as sp

from . import manufactured as mf
from .case import Case
from .geometry import PRISM, RING, Axis, Force, Motion, Probe, Section, Support
from .material import Material

#: the prism's length; the ring's section spans r in [1, 2]
LENGTH = 2.0
OMEGA = 3.0
NU = 0.3
#: the variation's mode: E and rho ~ 1 + a cos(2 k x3)
VARIATION_MODE = 2
#: the probe point (x1, x2, x3) of each body: a node of every refined mesh, the reference's
#: x3 divisions uniform and nested through it (a break point off the grid made its x3
#: elements uneven and not halved, which spoils a nodal order)
POINTS = {PRISM: (0.5, 0.5, 0.75), RING: (1.5, 0.5, math.pi / 4)}
SPANS = {PRISM: ((0.0, 1.0), (0.0, 1.0)), RING: ((1.0, 2.0), (0.0, 1.0))}
#: the mesh before refine: 4 x 4 elements
PAPER_COUNTS = 4
DEFAULTS = dict(dt=2.5e-3, t_end=1.0, refine=1, harmonics=6, a=0.3, dim=2, free_top=False, time="cos", tol=1e-5)
TIME_FUNCTIONS = {"cos": 1 - sp.cos(OMEGA * mf.T), "quadratic": mf.T**2}


def motion(body: str, free_top: bool = False) -> list[sp.Expr]:
    """``U(x1, x2, x3)``: the bubble times harmonics 1-3 (prism: sin in u1, u2, cos in u3;
    ring: cos in u_r, u_z with the axisymmetric term, sin in u_theta)."""
    x1, x2, x3 = mf.X1, mf.X2, mf.X3
    (s0, s1), (t0, t1) = SPANS[body]
    s, t = (x1 - s0) / (s1 - s0), (x2 - t0) / (t1 - t0)
    # a quadratic bubble times a gentle exponential: in no element's space (a quadratic bubble
    # alone is exact in the reference's section), with small higher derivatives, so that the
    # reference's 2 x 2 section elements are already in the asymptotic range (a sin sin bubble,
    # half a wave over two elements, gave its ring an L2 order of 2.56 there, against 2.96)
    # free_top: t (3 - t) / 2 in x2, neither zero nor flat on the top edge (a flat top would
    # leave the traction little to do)
    across = t * (3 - t) / 2 if free_top else 4 * t * (1 - t)
    bubble = 4 * s * (1 - s) * across * sp.exp((s + t) / 2)
    if body == PRISM:
        k = sp.pi / LENGTH
        return [bubble * (sp.sin(k * x3) + sp.sin(3 * k * x3) / 2), bubble * sp.sin(2 * k * x3),
                bubble * (sp.cos(k * x3) / 2 + sp.cos(3 * k * x3) / 3)]
    return [bubble * (1 + sp.cos(x3) / 2 + sp.cos(3 * x3) / 3), bubble * (sp.cos(2 * x3) + sp.Rational(1, 4)),
            bubble * (sp.sin(x3) - sp.sin(2 * x3) / 2)]


def time_function(name: str = "cos") -> sp.Expr:
    if name not in TIME_FUNCTIONS:
        raise ValueError(f"time must be one of {sorted(TIME_FUNCTIONS)}, not {name!r}")
    return TIME_FUNCTIONS[name]


def build(body: str, params: dict | None = None) -> Case:
    """The manufactured scene of ``body`` (``'prism'`` or ``'ring'``) at ``params`` (over :data:`DEFAULTS`)."""
    p = {**DEFAULTS, **(params or {})}
    k = 1 if body == RING else sp.pi / LENGTH
    factor = 1 + p["a"] * sp.cos(VARIATION_MODE * k * mf.X3)
    U, time = motion(body, p["free_top"]), time_function(p["time"])
    terms = mf.motion_body_forces(U, time, body, factor, NU, factor)
    if p["free_top"]:  # the top edge (x2 = max, normal +x2) loaded by sigma(U) n
        top = [c.subs(mf.X2, SPANS[body][1][1]) for c in mf.traction(U, body, factor, NU, (0, 1, 0))]
        terms += (Force(tuple(str(c) for c in top), str(time), edge="t_max"),)
    fixed = ("s_min", "s_max", "t_min") + (() if p["free_top"] else ("t_max",))
    (s0, s1), (t0, t1) = SPANS[body]
    section = Section("rect", s=Axis((s0, s1), (PAPER_COUNTS,)), t=Axis((t0, t1), (PAPER_COUNTS,)), edges={})
    point = POINTS[body]
    params = dict(p, E=1.0, nu=NU, rho=1.0, tau_s=math.inf, plastic=False)
    return Case(
        name=f"manufactured_{body}", title=f"Manufactured motion of a {body} (code verification)", body=body,
        section=section, length=LENGTH if body == PRISM else 2 * math.pi, material=Material(1.0, NU, 1.0),
        loads=(), supports=tuple(Support(e, (1, 2, 3)) for e in fixed),
        probes=(Probe("u1", "point", "u", (1,), point=point), Probe("u2", "point", "u", (2,), point=point),
                Probe("u3", "point", "u", (3,), point=point)),
        params=params, forces=terms, exact=Motion(tuple(str(c) for c in U), str(time)), variation=((p["a"], VARIATION_MODE),) if p["a"] else (),
        symmetric=True, units="dimensionless (E = rho = 1)",
        provenance={"ours": "the whole scene: a chosen motion and the body force that makes it exact"},
    )


def exact(case, t: np.ndarray) -> dict[str, np.ndarray]:
    """The probes' exact histories at times ``t``."""
    U, time = motion(case.body, case.params.get("free_top", False)), time_function(case.params.get("time", "cos"))
    return probe_histories(case.probes, U, time, t)


def probe_histories(probes, U: list, time, t: np.ndarray) -> dict[str, np.ndarray]:
    """Point probes' histories at times ``t`` of the motion ``U`` (body components) times ``time``."""
    out = {}
    for probe in probes:
        x1, x2, x3 = probe.point
        value = (U[probe.component[0] - 1] * time).subs({mf.X1: x1, mf.X2: x2, mf.X3: x3})
        out[probe.name] = np.asarray(sp.lambdify(mf.T, value, "numpy")(np.asarray(t, float)), float) + 0.0 * t
    return out
