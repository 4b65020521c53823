"""Exact closed-form solutions used as references by both solvers' tests and the reports.

All functions are vectorised (numpy broadcasting over the coordinate and load arguments), use
any consistent unit system (SI in this project: m, Pa) and take the elastic constants as
Young's modulus ``E`` and Poisson's ratio ``nu``; the conversion to Lame constants is done only
through :func:`cases.material.lame`, so ``nu`` must be strictly below 0.5.

Sign conventions (all functions): stresses are positive in tension; a *pressure* is positive
when it pushes on the surface (compressive normal traction ``sigma_nn = -p``).

Functions
---------
lame_cylinder
    Thick-walled cylinder under internal and external pressure (plane strain or plane stress).
compound_cylinder
    Two bonded Lame layers of different materials under internal and external pressure.
hinged_strip_sine
    Exact 2-D plane-strain elasticity solution of a simply supported (diaphragm) strip under a
    sinusoidal pressure on its top face (Airy stress function; "cylindrical bending").
hill_cylinder
    Elastic-ideally-plastic expansion of a plane-strain thick cylinder under internal pressure.

The 1-D rod impact reference lives in :func:`cases.rod_impact.rod_theory`.
"""

from __future__ import annotations

import numpy as np

from .material import lame

__all__ = ["lame_cylinder", "compound_cylinder", "hinged_strip_sine", "hill_cylinder"]


# --------------------------------------------------------------------------------------------
# 1. Lame thick cylinder
# --------------------------------------------------------------------------------------------
def lame_cylinder(r, a, b, p_in, p_out, E, nu, plane="strain"):
    """Lame solution of a thick-walled cylinder under uniform internal and external pressure.

    Parameters
    ----------
    r : array_like
        Radius (length), normally ``a <= r <= b``; the formulas are evaluated as they are
        outside that range too.
    a, b : float or array_like
        Inner and outer radius (length), ``0 < a < b``.
    p_in, p_out : float or array_like
        Pressure (stress units) on the inner surface ``r = a`` and on the outer surface
        ``r = b``; positive = compressive on the surface, so ``sigma_rr(a) = -p_in`` and
        ``sigma_rr(b) = -p_out``.
    E, nu : float
        Young's modulus (stress units) and Poisson's ratio (``nu < 0.5``).
    plane : {'strain', 'stress'}
        ``'strain'``: infinite cylinder, ``eps_zz = 0``, ``sigma_zz = nu (sigma_rr + sigma_tt)``.
        ``'stress'``: thin disc/ring, ``sigma_zz = 0`` (``eps_zz`` is not returned).

    Returns
    -------
    dict of ndarray
        ``u_r`` radial displacement (length, positive outward), ``sigma_rr``, ``sigma_tt``
        (hoop) and ``sigma_zz`` (axial) stress, all broadcast to a common shape.

    Notes
    -----
    ``sigma_rr = A - B / r**2``, ``sigma_tt = A + B / r**2`` with
    ``A = (p_in a^2 - p_out b^2) / (b^2 - a^2)`` and ``B = (p_in - p_out) a^2 b^2 / (b^2 - a^2)``;
    the displacement ``u_r = alpha r + beta / r`` with ``beta = B / (2 mu)`` and
    ``alpha = A / (2 (lambda + mu))`` in plane strain (``lambda`` replaced by
    ``2 lambda mu / (lambda + 2 mu)`` in plane stress). No rigid-body motion is possible
    in axisymmetric deformation, so the solution is unique.

    Source: Timoshenko & Goodier, *Theory of Elasticity*, 3rd ed. (1970), ch. 4, thick-walled
    cylinder (Lame, 1852); Barber, *Elasticity*, 3rd ed. (2010), ch. 8.
    """
    if plane not in ("strain", "stress"):
        raise ValueError(f"plane must be 'strain' or 'stress', not {plane!r}")
    r = np.asarray(r, dtype=float)
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    p_in, p_out = np.asarray(p_in, dtype=float), np.asarray(p_out, dtype=float)
    d = b**2 - a**2
    A = (p_in * a**2 - p_out * b**2) / d
    B = (p_in - p_out) * a**2 * b**2 / d
    return _lame_field(r, A, B, E, nu, plane)


def _lame_field(r, A, B, E, nu, plane="strain"):
    """Lame field from its constants: ``sigma_rr = A - B / r^2``, ``sigma_tt = A + B / r^2``."""
    lam, mu = lame(E, nu)
    if plane == "stress":
        lam = 2.0 * lam * mu / (lam + 2.0 * mu)
    sigma_rr = A - B / r**2
    sigma_tt = A + B / r**2
    u_r = A / (2.0 * (lam + mu)) * r + B / (2.0 * mu) / r
    if plane == "strain":
        sigma_zz = 2.0 * nu * A * np.ones_like(sigma_rr)
    else:
        sigma_zz = np.zeros_like(sigma_rr)
    out = dict(u_r=u_r, sigma_rr=sigma_rr, sigma_tt=sigma_tt, sigma_zz=sigma_zz)
    shape = np.broadcast_shapes(*(np.shape(val) for val in out.values()))
    return {key: np.broadcast_to(val, shape).copy() for key, val in out.items()}


def compound_cylinder(r, radii, E, nu, p_inner, p_outer, plane="strain"):
    """Two bonded layers (a compound cylinder) under uniform internal and external pressure.

    Parameters
    ----------
    r : array_like
        Radius (length), normally ``a <= r <= c``: the inner layer's field for ``r <= b``, the
        outer's beyond.
    radii : (a, b, c)
        Inner radius, interface and outer radius (length), ``0 < a < b < c``.
    E, nu : (inner, outer)
        Each layer's Young's modulus (stress units) and Poisson's ratio (``nu < 0.5``).
    p_inner, p_outer : float or array_like
        Pressure (stress units) on ``r = a`` and on ``r = c``, positive = compressive on the
        surface, as in :func:`lame_cylinder`: ``sigma_rr(a) = -p_inner``, ``sigma_rr(c) = -p_outer``.
    plane : {'strain', 'stress'}
        As in :func:`lame_cylinder`.

    Returns
    -------
    dict of ndarray
        ``u_r`` (length, positive outward), ``sigma_rr``, ``sigma_tt``, ``sigma_zz`` (stress
        units; at ``r = b`` the inner layer's hoop and axial stress: they jump there) and
        ``p_interface``, the contact pressure at ``r = b`` (compression positive), all broadcast
        to a common shape.

    Notes
    -----
    Each layer is a Lame cylinder (:func:`lame_cylinder`): the inner one under ``p_inner`` and
    the interface pressure ``p_b``, the outer one under ``p_b`` and ``p_outer``; ``sigma_rr`` is
    continuous at ``b`` by construction, and ``p_b`` makes ``u_r`` continuous there. Each
    layer's ``u_r(b)`` is linear in its two pressures, so with ``u_in = u_in0 + p_b u_in1`` and
    ``u_out = u_out0 + p_b u_out1`` (``u_in1 < 0 < u_out1``),
    ``p_b = (u_out0 - u_in0) / (u_in1 - u_out1)``.

    Source: Timoshenko & Goodier, *Theory of Elasticity*, 3rd ed. (1970), ch. 4 (shrink-fit
    and compound cylinders); Barber, *Elasticity*, 3rd ed. (2010), ch. 8.
    """
    a, b, c = radii
    (E1, E2), (nu1, nu2) = E, nu
    r = np.asarray(r, dtype=float)
    p_inner, p_outer = np.asarray(p_inner, dtype=float), np.asarray(p_outer, dtype=float)

    def inner(p_b, rr=b):
        return lame_cylinder(rr, a, b, p_inner, p_b, E1, nu1, plane)

    def outer(p_b, rr=b):
        return lame_cylinder(rr, b, c, p_b, p_outer, E2, nu2, plane)

    u_in0, u_out0 = inner(0.0)["u_r"], outer(0.0)["u_r"]
    # per unit interface pressure alone (the layers' own loads off)
    u_in1 = lame_cylinder(b, a, b, 0.0, 1.0, E1, nu1, plane)["u_r"]
    u_out1 = lame_cylinder(b, b, c, 1.0, 0.0, E2, nu2, plane)["u_r"]
    p_b = (u_out0 - u_in0) / (u_in1 - u_out1)
    fields_in, fields_out = inner(p_b, r), outer(p_b, r)
    out = {key: np.where(r <= b, fields_in[key], fields_out[key]) for key in fields_in}
    out["p_interface"] = p_b
    shape = np.broadcast_shapes(*(np.shape(val) for val in out.values()))
    return {key: np.broadcast_to(val, shape).copy() for key, val in out.items()}


# --------------------------------------------------------------------------------------------
# 2. Hinged strip, sinusoidal load: exact plane-strain elasticity ("cylindrical bending")
# --------------------------------------------------------------------------------------------
def _strip_F(c, t, m):
    """m-th derivative of ``F(t) = (c0 + c1 t) cosh t + (c2 + c3 t) sinh t``."""
    P, Q = (c[0], c[1]), (c[2], c[3])
    for _ in range(m):
        # d/dt[(p0 + p1 t) ch + (q0 + q1 t) sh] = (p1 + q0 + q1 t) ch + (q1 + p0 + p1 t) sh
        P, Q = (P[1] + Q[0], Q[1]), (Q[1] + P[0], P[1])
    return (P[0] + P[1] * t) * np.cosh(t) + (Q[0] + Q[1] * t) * np.sinh(t)


def _strip_coefficients(kh):
    """Solve the 4x4 face-condition system for the scaled stress function F.

    Unknowns ``(A, B, C, D)`` of ``F(t) = (A + B t) cosh t + (C + D t) sinh t``, ``t = k z``;
    conditions ``F(0) = 0, F'(0) = 0`` (bottom traction-free), ``F(kh) = 1, F'(kh) = 0``
    (top: ``sigma_zz = -q0 sin kx``, ``sigma_xz = 0``).
    """
    ch, sh = np.cosh(kh), np.sinh(kh)
    M = np.array(
        [
            [1.0, 0.0, 0.0, 0.0],  # F(0)
            [0.0, 1.0, 1.0, 0.0],  # F'(0)
            [ch, kh * ch, sh, kh * sh],  # F(kh)
            [sh, ch + kh * sh, ch, sh + kh * ch],  # F'(kh)
        ]
    )
    return np.linalg.solve(M, np.array([0.0, 0.0, 1.0, 0.0]))


def hinged_strip_sine(x, z, L, h, q0, E, nu, n=1):
    """Exact plane-strain solution of a hinged strip under a sinusoidal top-face pressure.

    A strip (plate of infinite width, plane strain in ``x``-``z``) of span ``0 <= x <= L`` and
    thickness ``0 <= z <= h``; the ends ``x = 0, L`` are diaphragm ("hinged") supports:
    ``u_z = 0`` and ``sigma_xx = 0`` over the whole thickness, ``u_x`` free. The top face
    ``z = h`` carries the pressure ``p(x) = q0 sin(n pi x / L)`` pressing downward (towards
    ``-z``): ``sigma_zz(x, h) = -p(x)``, ``sigma_xz(x, h) = 0``. The bottom face ``z = 0`` is
    traction-free. No body forces.

    Parameters
    ----------
    x, z : array_like
        Span and height coordinates (length); they broadcast against each other.
    L, h : float
        Span and thickness (length).
    q0 : float
        Load amplitude (stress units); positive = pressing downward on the top face.
    E, nu : float
        Young's modulus (stress units) and Poisson's ratio (``nu < 0.5``).
    n : int
        Number of half-waves of the load along the span.

    Returns
    -------
    dict of ndarray
        ``u_x``, ``u_z`` displacements (length; ``u_z`` positive upward, so the deflection
        under a positive ``q0`` is negative), ``sigma_xx``, ``sigma_zz``, ``sigma_xz``
        (stress units, tension positive).

    Notes
    -----
    Airy stress function ``phi = sin(k x) f(z)``, ``k = n pi / L``, with
    ``sigma_xx = phi_zz``, ``sigma_zz = phi_xx``, ``sigma_xz = -phi_xz``; the biharmonic
    equation gives ``f = (A + B z) cosh kz + (C + D z) sinh kz``. Written as
    ``f = (q0 / k^2) F(kz)``, the stresses are

        sigma_xx = q0 sin(kx) F''(kz),  sigma_zz = -q0 sin(kx) F(kz),
        sigma_xz = -q0 cos(kx) F'(kz),

    and the face conditions ``F(0) = F'(0) = 0``, ``F(kh) = 1``, ``F'(kh) = 0`` form the 4x4
    system for ``A..D`` (solved numerically). ``sigma_xx = 0`` at the ends holds identically.
    Integrating the plane-strain strains ``eps_xx = a1 sigma_xx - a2 sigma_zz``,
    ``eps_zz = a1 sigma_zz - a2 sigma_xx``, ``gamma_xz = sigma_xz / mu``
    (``a1 = (1 - nu^2) / E``, ``a2 = nu (1 + nu) / E``) gives exactly

        u_x = -(q0 / k) cos(kx) [a1 F'' + a2 F],
        u_z = (q0 / k) sin(kx) [a1 F''' + (a2 - 1 / mu) F'],

    where the integration function of ``u_z`` is fixed by the shear-strain compatibility and
    the rigid-body motion (translation, rotation) is zero by the hinge conditions
    ``u_z(0, z) = u_z(L, z) = 0`` and by taking ``u_x`` purely ``~ cos(kx)``.
    Thin limit (``h / L -> 0``): the mid-span deflection tends to the plane-strain plate
    value ``w_pl = -q0 L^4 / (n^4 pi^4 D)``, ``D = E h^3 / (12 (1 - nu^2))``. The mid-plane
    deflection expands as ``w_pl (1 + (8 - 3 nu) / (40 (1 - nu)) (kh)^2 + ...)`` (checked
    numerically in tests/test_analytic.py), while Mindlin/Timoshenko with ``kappa = 5/6``
    gives ``w_pl (1 + (kh)^2 / (5 (1 - nu)))``: equal for ``nu = 0``, and for ``nu > 0`` the
    exact mid-plane deflection is slightly *smaller* than Mindlin's (the transverse normal
    strain is ignored there); e.g. h/L = 1/3, nu = 0.3: exact 0.970 x Mindlin, 1.273 x plate.
    ``u_z`` varies through the thickness (largest magnitude near the mid-plane).

    The face system is solved in the scaled variable ``t = k z``; cancellation grows as
    ``h / L -> 0`` (relative error of ``u_z`` about 1e-10 at ``h / L = 1e-3``, 1e-8 at 1e-4).

    Source: Timoshenko & Goodier, *Theory of Elasticity*, 3rd ed. (1970), ch. 3, "Solution of
    the two-dimensional problem in the form of a Fourier series"; Pagano, N. J., "Exact
    solutions for composite laminates in cylindrical bending", J. Compos. Mater. 3 (1969)
    398-411 (isotropic single-layer case).
    """
    x, z = np.asarray(x, dtype=float), np.asarray(z, dtype=float)
    k = n * np.pi / L
    c = _strip_coefficients(k * h)
    t = k * z
    F0, F1, F2, F3 = (_strip_F(c, t, m) for m in range(4))
    lam, mu = lame(E, nu)
    s = 1.0 / (4.0 * mu * (lam + mu))
    a1, a2 = (lam + 2.0 * mu) * s, lam * s  # (1 - nu^2)/E, nu (1 + nu)/E
    sn, cs = np.sin(k * x), np.cos(k * x)
    out = dict(
        u_x=-(q0 / k) * cs * (a1 * F2 + a2 * F0),
        u_z=(q0 / k) * sn * (a1 * F3 + (a2 - 1.0 / mu) * F1),
        sigma_xx=q0 * sn * F2,
        sigma_zz=-q0 * sn * F0,
        sigma_xz=-q0 * cs * F1,
    )
    shape = np.broadcast_shapes(x.shape, z.shape)
    return {key: np.broadcast_to(val, shape).copy() for key, val in out.items()}


# --------------------------------------------------------------------------------------------
# 3. Hill: elastic-ideally-plastic thick cylinder under internal pressure (plane strain)
# --------------------------------------------------------------------------------------------
def hill_cylinder(p, a, b, k, E, nu, r=None):
    """Elastic-ideally-plastic plane-strain thick cylinder under internal pressure.

    Parameters
    ----------
    p : float or array_like
        Internal pressure (stress units, positive = compressive on ``r = a``), ``0 <= p <= p_c``.
    a, b : float
        Inner and outer radius (length); the outer surface is traction-free.
    k : float
        Yield stress in shear (stress units; the project's ``tau_s``): yield when
        ``sigma_tt - sigma_rr = 2 k``.
    E, nu : float
        Young's modulus (stress units) and Poisson's ratio (``nu < 0.5``).
    r : array_like, optional
        Radii at which to return the stresses (broadcast against ``p``).

    Returns
    -------
    dict
        ``c`` elastic-plastic interface radius (length; ``c = a`` while elastic),
        ``u_b`` radial displacement of the outer surface (length, positive outward),
        ``p_y`` first-yield pressure and ``p_c`` collapse pressure (stress units);
        with ``r`` also ``sigma_rr`` and ``sigma_tt`` there (stress units, tension positive).

    Raises
    ------
    ValueError
        If any ``p`` exceeds the collapse pressure ``p_c`` (or is negative).

    Notes
    -----
    Yield criterion ``sigma_tt - sigma_rr = 2 k``: Tresca with shear yield stress ``k`` when
    ``sigma_zz`` is the intermediate principal stress, and von Mises (``sigma_y = sqrt(3) k``)
    in plane strain when ``sigma_zz = (sigma_rr + sigma_tt) / 2``, which holds exactly in the
    plastic zone for ``nu = 0.5`` (incompressibility). For other ``nu`` the results are exact
    for that yield condition; with von Mises they are an approximation in the plastic zone, but
    the elastic region ``c <= r <= b`` is still an exact Lame cylinder as long as the plastic
    zone satisfies ``sigma_tt - sigma_rr = 2 k`` (the stresses are statically determined).

    - plastic zone ``a <= r <= c``: ``sigma_rr = -p + 2 k ln(r / a)``,
      ``sigma_tt = sigma_rr + 2 k``;
    - elastic zone ``c <= r <= b``: Lame cylinder with internal pressure
      ``k (1 - c^2 / b^2)`` at ``r = c``, outer surface free;
    - ``p_y = k (1 - a^2 / b^2)``; for ``p_y <= p <= p_c`` the radius ``c`` solves
      ``p = 2 k ln(c / a) + k (1 - c^2 / b^2)`` (monotonic in ``c``); ``p_c = 2 k ln(b / a)``;
    - ``u_b = 2 (1 - nu^2) k c^2 / (E b)`` in the elastic-plastic range, the Lame value
      ``2 (1 - nu^2) p a^2 b / (E (b^2 - a^2))`` below ``p_y``; continuous at ``p_y``.

    ``c`` is found by bisection to machine precision, except close to collapse where
    ``dp/dc -> 0`` limits it to about ``sqrt(machine eps)`` relative; ``c = b`` at ``p = p_c``.

    Source: Hill, *The Mathematical Theory of Plasticity* (1950), ch. V (expansion of a
    cylindrical tube); Chakrabarty, *Theory of Plasticity*, 3rd ed. (2006), thick-walled tube.
    """
    p = np.asarray(p, dtype=float)
    p_y = k * (1.0 - a**2 / b**2)
    p_c = 2.0 * k * np.log(b / a)
    if np.any(p > p_c * (1.0 + 1e-12)) or np.any(p < 0.0):
        raise ValueError(f"pressure must lie in [0, p_c = {p_c:.6g}] (collapse)")
    p = np.minimum(p, p_c)
    # bisection on s = ln(c / a) in [0, ln(b / a)]: g(s) = 2 k s + k (1 - a^2 e^{2s} / b^2) - p
    lo = np.zeros_like(p)
    hi = np.full_like(p, np.log(b / a))
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        g = 2.0 * k * mid + k * (1.0 - a**2 * np.exp(2.0 * mid) / b**2) - p
        lo, hi = np.where(g < 0.0, mid, lo), np.where(g < 0.0, hi, mid)
    c = np.where(p <= p_y, a, a * np.exp(0.5 * (lo + hi)))
    # near collapse dp/dc -> 0: c is only ~sqrt(machine eps) accurate there; exact at p_c
    c = np.where(p >= p_c, b, c)
    # elastic region c <= r <= b: Lame constants (outer surface free, so B = A b^2); below
    # p_y the whole wall with p at r = a, above it k (1 - c^2 / b^2) at r = c, i.e. A = k c^2/b^2
    A = np.where(p <= p_y, p * a**2 / (b**2 - a**2), k * c**2 / b**2)
    u_b = _lame_field(b, A, A * b**2, E, nu)["u_r"]
    out = dict(c=c, u_b=u_b, p_y=p_y, p_c=p_c)
    if r is not None:
        r = np.asarray(r, dtype=float)
        el = _lame_field(r, A, A * b**2, E, nu)
        s_rr_pl = -p + 2.0 * k * np.log(r / a)
        plastic = r < c
        out["sigma_rr"] = np.where(plastic, s_rr_pl, el["sigma_rr"])
        out["sigma_tt"] = np.where(plastic, s_rr_pl + 2.0 * k, el["sigma_tt"])
    return out
