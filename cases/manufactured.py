"""Manufactured solutions: a chosen displacement field and the body force that makes it exact.

Code verification (Roache; Salari & Knupp) runs a solver on a problem whose exact solution is
chosen first: the equations of motion then say which loads produce it. Here the source terms
are derived symbolically (sympy) from the chosen field, never by hand:

    b = rho u_tt - div sigma(u),   sigma = lambda tr(eps) I + 2 mu eps,

in the body's own coordinates (:mod:`cases.geometry`): a prism's are cartesian ``(x1, x2, x3)``;
a ring's are cylindrical ``(r, z, theta) = (x1, x2, x3)`` with the components ``u_r, u_z,
u_theta``, whose strains and divergence carry the curvature terms. The material may vary along
x3 (``E`` and ``rho`` given as expressions of x3), which is what couples the harmonics in SMFEM.

Strains and stresses are Voigt ``[11, 22, 33, 12, 13, 23]`` (engineering shears in the strains,
as :mod:`smfem.plasticity` stores them). Everything here is data: sympy expressions, and the
strings a case or a scene file holds, read by :func:`cases.expressions.parse` (a whitelist:
nothing in a string runs as code); :func:`numeric` turns one into a numpy function of
``(x1, x2, x3, t)`` for either solver to evaluate at its own points.
"""

from __future__ import annotations

import functools

import numpy as np
import sympy as sp

# the symbols and the parser live with the whitelist; the solvers and tests read them here
from .expressions import VARIABLES, X1, X2, X3, ExpressionError, T, parse
from .geometry import PRISM, RING
from .params import failure


@functools.lru_cache(maxsize=256)
def numeric(text: str):
    """``f(x1, x2, x3, t)`` of an expression string, vectorised over numpy arrays (a constant
    comes back broadcast to the shape of its arguments); an :class:`ExpressionError` where numpy
    cannot evaluate it (``sin(10**300)``: an integer past int64 in a ufunc) or gives complex
    values (``(-1)**(1/3)``: a constant's complex root)."""
    f = sp.lambdify(VARIABLES, parse(text), "numpy")

    def g(x1, x2, x3, t):
        return np.broadcast_to(f(x1, x2, x3, t), np.broadcast(x1, x2, x3, t).shape)

    try:
        with np.errstate(all="ignore"):  # an overflow or 1/x1 at the sample is the solver's to meet
            sample = np.asarray(g(*[np.full(2, 0.5)] * 4))
        if not np.iscomplexobj(sample):
            sample.astype(float)  # an object array (of integers past int64) fails here
    except (ArithmeticError, TypeError, ValueError) as exc:
        raise ExpressionError(f"numpy cannot evaluate it ({failure(exc)})") from None
    if np.iscomplexobj(sample):
        raise ExpressionError("its values are complex (a root of a negative number?)")
    return g


def time_function(text: str):
    """``g(t)`` of a force's time expression, a float for a float ``t``."""
    g = numeric(text)
    return lambda t: float(g(0.0, 0.0, 0.0, t))


def forces_invariant(forces, section, period: float, x3_image, signs=(1.0, 1.0, 1.0)) -> bool:
    """Whether force terms (:class:`cases.geometry.Force`) are unchanged by the map
    ``x3 -> x3_image(x3)`` with the components' ``signs`` (a reflection turns the x3 component;
    the identity with sign -1 on it asks whether that component is zero), tried at sample points
    of ``section`` and along ``period``."""
    rng = np.random.default_rng(1)
    if getattr(section, "kind", "") == "mesh":
        x1, x2 = section.inside(3)
    else:
        (s0, s1), (t0, t1) = section.s.span, section.t.span
        x1, x2 = section.to_x(s0 + (s1 - s0) * rng.random(5), t0 + (t1 - t0) * rng.random(5))
    x3 = (np.arange(97) + 0.5 * 2 ** 0.5) * period / 97  # off any simple fraction of the period
    x1, x2, x3 = np.asarray(x1)[:, None], np.asarray(x2)[:, None], x3[None, :]
    for force in forces:
        for c, sign in zip(force.pattern, signs):
            f = numeric(c)
            with np.errstate(all="ignore"):  # a force past a float's range is refused where it is read
                a, b = np.asarray(f(x1, x2, x3, 0.0), float), sign * np.asarray(f(x1, x2, x3_image(x3), 0.0), float)
                if not np.allclose(a, b, rtol=1e-9, atol=1e-12 * (1 + np.abs(a).max())):
                    return False
    return True


def strains(u, body: str) -> list[sp.Expr]:
    """Voigt small strains (engineering shears) of the displacement components ``u``."""
    u1, u2, u3 = u
    d = sp.diff
    if body == PRISM:
        return [d(u1, X1), d(u2, X2), d(u3, X3),
                d(u1, X2) + d(u2, X1), d(u1, X3) + d(u3, X1), d(u2, X3) + d(u3, X2)]
    if body != RING:
        raise ValueError(f"body {body!r}")
    r = X1  # (r, z, theta): u1 = u_r, u2 = u_z, u3 = u_theta
    return [d(u1, r), d(u2, X2), (u1 + d(u3, X3)) / r,
            d(u1, X2) + d(u2, r), d(u1, X3) / r + d(u3, r) - u3 / r, d(u3, X2) + d(u2, X3) / r]


def stresses(u, body: str, E, nu) -> list[sp.Expr]:
    """Voigt stresses of an isotropic material (``E`` may vary in space)."""
    E, nu = sp.sympify(E), sp.sympify(nu)
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    e = strains(u, body)
    trace = e[0] + e[1] + e[2]
    return [lam * trace + 2 * mu * e[0], lam * trace + 2 * mu * e[1], lam * trace + 2 * mu * e[2],
            mu * e[3], mu * e[4], mu * e[5]]


def divergence(s, body: str) -> list[sp.Expr]:
    """``div sigma`` of Voigt stresses, per component."""
    s11, s22, s33, s12, s13, s23 = s
    d = sp.diff
    if body == PRISM:
        return [d(s11, X1) + d(s12, X2) + d(s13, X3),
                d(s12, X1) + d(s22, X2) + d(s23, X3),
                d(s13, X1) + d(s23, X2) + d(s33, X3)]
    r = X1  # cylindrical: 1 = r, 2 = z, 3 = theta
    return [d(s11, r) + d(s12, X2) + d(s13, X3) / r + (s11 - s33) / r,
            d(s12, r) + d(s22, X2) + d(s23, X3) / r + s12 / r,
            d(s13, r) + d(s23, X2) + d(s33, X3) / r + 2 * s13 / r]


def body_force(u, body: str, E, nu, rho) -> list[sp.Expr]:
    """The body force per unit volume that makes ``u`` an exact motion: ``rho u_tt - div sigma``."""
    rho = sp.sympify(rho)
    return [rho * sp.diff(ui, T, 2) - di for ui, di in zip(u, divergence(stresses(u, body, E, nu), body))]


def traction(u, body: str, E, nu, normal) -> list[sp.Expr]:
    """``sigma n`` on a surface of outward unit normal ``normal`` (components 1, 2, 3)."""
    return list(_traction(tuple(u), body, E, nu, tuple(normal)))


# the manufactured scenes are built again at every mesh, step and harmonic count of a study with
# the same motion and material: their terms are derived once (sympy, 0.5-3 s a scene)
@functools.lru_cache(maxsize=64)
def _traction(u: tuple, body: str, E, nu, normal: tuple) -> tuple:
    s11, s22, s33, s12, s13, s23 = stresses(u, body, E, nu)
    tensor = sp.Matrix([[s11, s12, s13], [s12, s22, s23], [s13, s23, s33]])
    return tuple(tensor * sp.Matrix(normal))


def motion_body_forces(U, time, body: str, E, nu, rho) -> tuple:
    """The body-force terms (:class:`cases.geometry.Force`) that make ``U(x) time(t)`` an
    exact motion: ``rho U`` times ``time''`` and ``-div sigma(U)`` times ``time``."""
    return _motion_body_forces(tuple(U), time, body, E, nu, rho)


@functools.lru_cache(maxsize=64)
def _motion_body_forces(U: tuple, time, body: str, E, nu, rho) -> tuple:
    from .geometry import Force

    time, rho = sp.sympify(time), sp.sympify(rho)
    inertia = Force(tuple(str(rho * Ui) for Ui in U), str(sp.diff(time, T, 2)))
    elastic = Force(tuple(str(-d) for d in divergence(stresses(U, body, E, nu), body)), str(time))
    return inertia, elastic
