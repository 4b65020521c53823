"""Self-checks of the closed-form references in cases/analytic.py (field equations by finite
differences, boundary conditions, limits, continuity)."""

import numpy as np
import pytest

from cases.analytic import hill_cylinder, hinged_strip_sine, lame_cylinder
from cases.material import lame

E, NU = 2.1e11, 0.3


def _d(f, x, h):
    """Central difference of f at x with step h."""
    return (f(x + h) - f(x - h)) / (2 * h)


# ------------------------------------------------------------------------------------ Lame
@pytest.mark.parametrize("plane", ["strain", "stress"])
@pytest.mark.parametrize("p_in,p_out", [(1e7, 0.0), (0.0, 3e7), (2e7, 5e6)])
def test_lame_equilibrium_tractions_hooke(plane, p_in, p_out):
    a, b = 1.0, 2.0
    r = np.linspace(a + 0.01, b - 0.01, 41)
    dr = 1e-5
    f = lambda rr: lame_cylinder(rr, a, b, p_in, p_out, E, NU, plane)
    s = f(r)
    scale = max(p_in, p_out)
    # equilibrium: d sigma_rr / dr + (sigma_rr - sigma_tt) / r = 0
    res = _d(lambda rr: f(rr)["sigma_rr"], r, dr) + (s["sigma_rr"] - s["sigma_tt"]) / r
    assert np.max(np.abs(res)) < 1e-6 * scale
    # boundary tractions
    assert f(a)["sigma_rr"] == pytest.approx(-p_in, abs=1e-9 * scale)
    assert f(b)["sigma_rr"] == pytest.approx(-p_out, abs=1e-9 * scale)
    # Hooke's law from the displacement: eps_rr = du/dr, eps_tt = u/r
    err = _d(lambda rr: f(rr)["u_r"], r, dr)
    ett = s["u_r"] / r
    lam, mu = lame(E, NU)
    if plane == "strain":
        ezz = 0.0
    else:  # sigma_zz = 0 fixes eps_zz
        ezz = -lam * (err + ett) / (lam + 2 * mu)
    tr = err + ett + ezz
    np.testing.assert_allclose(lam * tr + 2 * mu * err, s["sigma_rr"], rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(lam * tr + 2 * mu * ett, s["sigma_tt"], rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(lam * tr + 2 * mu * ezz, s["sigma_zz"], rtol=0, atol=1e-6 * scale)


def test_lame_thin_ring_and_sign():
    # thin ring under internal pressure: hoop stress p R / t, expands outward
    R, t, p = 1.0, 1e-3, 1e5
    s = lame_cylinder(R, R - t / 2, R + t / 2, p, 0.0, E, NU)
    assert s["sigma_tt"] == pytest.approx(p * R / t, rel=1e-3)
    assert s["u_r"] > 0
    with pytest.raises(ValueError):
        lame_cylinder(R, 1.0, 2.0, p, 0.0, E, NU, plane="axial")


# ------------------------------------------------------------------------- hinged strip
L, H, Q0 = 0.3, 0.1, 1e6


def _plate(L, h, q0, E, nu, n=1):
    D = E * h**3 / (12 * (1 - nu**2))
    return q0 * (L / n) ** 4 / (np.pi**4 * D)


@pytest.mark.parametrize("n", [1, 3])
def test_strip_field_equations(n):
    x = np.linspace(0.02, L - 0.02, 13)[:, None]
    z = np.linspace(0.005, H - 0.005, 11)[None, :]
    f = lambda xx, zz: hinged_strip_sine(xx, zz, L, H, Q0, E, NU, n)
    s = f(x, z)
    dx = dz = 1e-5
    k = n * np.pi / L
    ddx = lambda key: (f(x + dx, z)[key] - f(x - dx, z)[key]) / (2 * dx)
    ddz = lambda key: (f(x, z + dz)[key] - f(x, z - dz)[key]) / (2 * dz)
    # equilibrium (no body force)
    res_x = ddx("sigma_xx") + ddz("sigma_xz")
    res_z = ddx("sigma_xz") + ddz("sigma_zz")
    smax = max(np.abs(s[key]).max() for key in ("sigma_xx", "sigma_zz", "sigma_xz"))
    assert np.abs(res_x).max() < 1e-6 * k * smax
    assert np.abs(res_z).max() < 1e-6 * k * smax
    # kinematics + plane-strain Hooke's law
    exx, ezz = ddx("u_x"), ddz("u_z")
    gxz = ddz("u_x") + ddx("u_z")
    lam, mu = lame(E, NU)
    tol = 1e-6 * smax
    np.testing.assert_allclose(lam * (exx + ezz) + 2 * mu * exx, s["sigma_xx"], rtol=0, atol=tol)
    np.testing.assert_allclose(lam * (exx + ezz) + 2 * mu * ezz, s["sigma_zz"], rtol=0, atol=tol)
    np.testing.assert_allclose(mu * gxz, s["sigma_xz"], rtol=0, atol=tol)


@pytest.mark.parametrize("n", [1, 2])
def test_strip_boundary_conditions(n):
    x = np.linspace(0, L, 31)
    z = np.linspace(0, H, 21)
    top = hinged_strip_sine(x, H, L, H, Q0, E, NU, n)
    bot = hinged_strip_sine(x, 0.0, L, H, Q0, E, NU, n)
    p = Q0 * np.sin(n * np.pi * x / L)
    atol = 1e-9 * Q0
    np.testing.assert_allclose(top["sigma_zz"], -p, rtol=0, atol=atol)
    np.testing.assert_allclose(top["sigma_xz"], 0, atol=atol)
    np.testing.assert_allclose(bot["sigma_zz"], 0, atol=atol)
    np.testing.assert_allclose(bot["sigma_xz"], 0, atol=atol)
    w = _plate(L, H, Q0, E, NU, n)
    for xe in (0.0, L):
        end = hinged_strip_sine(xe, z, L, H, Q0, E, NU, n)
        np.testing.assert_allclose(end["u_z"], 0, atol=1e-12 * w)
        np.testing.assert_allclose(end["sigma_xx"], 0, atol=atol)
    # broadcasting and shapes
    grid = hinged_strip_sine(x[:, None], z[None, :], L, H, Q0, E, NU, n)
    assert all(v.shape == (31, 21) for v in grid.values())


def test_strip_global_equilibrium():
    # stress resultants of any exact solution obey beam statics:
    # N = 0, V = -q0 cos(kx) / k, M (about mid-plane, sagging +) = -q0 sin(kx) / k^2
    k = np.pi / L
    z = np.linspace(0, H, 4001)
    for x in (0.05, L / 2, 0.27):
        s = hinged_strip_sine(x, z, L, H, Q0, E, NU)
        N = np.trapezoid(s["sigma_xx"], z)
        V = np.trapezoid(s["sigma_xz"], z)
        M = np.trapezoid(s["sigma_xx"] * (z - H / 2), z)
        assert abs(N) < 1e-6 * Q0 * H
        assert V == pytest.approx(-Q0 * np.cos(k * x) / k, abs=1e-6 * Q0 / k)
        assert M == pytest.approx(-Q0 * np.sin(k * x) / k**2, rel=1e-6)


def test_strip_thin_limit_plate():
    # h / L = 0.01: mid-span deflection within 0.5 % of q0 L^4 / (pi^4 D)
    L1, h1 = 1.0, 0.01
    w = _plate(L1, h1, Q0, E, NU)
    for z in (0.0, h1 / 2, h1):
        uz = hinged_strip_sine(L1 / 2, z, L1, h1, Q0, E, NU)["u_z"]
        assert uz < 0
        assert -uz == pytest.approx(w, rel=5e-3)


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.45])
def test_strip_thickness_correction(nu):
    # mid-plane deflection = plate * (1 + c (kh)^2 + ...): c = (8 - 3 nu) / (40 (1 - nu)),
    # Mindlin/Timoshenko (kappa = 5/6) has c = 1 / (5 (1 - nu)) -- equal for nu = 0, and the
    # exact mid-plane value is slightly below Mindlin for nu > 0
    L1, h1 = 1.0, 0.01
    kh = np.pi * h1 / L1
    w = _plate(L1, h1, 1.0, E, nu)
    uz = -hinged_strip_sine(L1 / 2, h1 / 2, L1, h1, 1.0, E, nu)["u_z"]
    assert (uz / w - 1) / kh**2 == pytest.approx((8 - 3 * nu) / (40 * (1 - nu)), rel=1e-3)


def test_strip_moderately_thick_vs_mindlin():
    # project strip (h / L = 1/3): exact mid-plane deflection between plate and Mindlin,
    # within 5 % of Mindlin
    w_pl = _plate(L, H, Q0, E, NU)
    _, mu = lame(E, NU)
    k = np.pi / L
    w_mi = w_pl + Q0 / (k**2 * (5 / 6) * mu * H)
    uz = -hinged_strip_sine(L / 2, H / 2, L, H, Q0, E, NU)["u_z"]
    assert w_pl < uz < w_mi
    assert uz == pytest.approx(w_mi, rel=0.05)


# ----------------------------------------------------------------------------------- Hill
A_, B_, K_ = 1.0, 2.0, 1.7e8


def test_hill_first_yield_continuity():
    h = hill_cylinder(0.0, A_, B_, K_, E, NU)
    p_y, p_c = h["p_y"], h["p_c"]
    assert p_y == pytest.approx(K_ * (1 - A_**2 / B_**2))
    assert p_c == pytest.approx(2 * K_ * np.log(B_ / A_))
    at = hill_cylinder(p_y, A_, B_, K_, E, NU)
    assert at["c"] == pytest.approx(A_, rel=1e-12)
    u_lame = lame_cylinder(B_, A_, B_, p_y, 0.0, E, NU)["u_r"]
    assert at["u_b"] == pytest.approx(u_lame, rel=1e-12)
    # just above first yield: continuous
    up = hill_cylinder(p_y * (1 + 1e-9), A_, B_, K_, E, NU)
    assert up["c"] == pytest.approx(A_, rel=1e-6)
    assert up["u_b"] == pytest.approx(u_lame, rel=1e-6)
    # below first yield: Lame, and Lame yields first at r = a exactly at p_y
    p = np.linspace(0, p_y, 7)
    np.testing.assert_allclose(
        hill_cylinder(p, A_, B_, K_, E, NU)["u_b"], lame_cylinder(B_, A_, B_, p, 0, E, NU)["u_r"]
    )
    s = lame_cylinder(A_, A_, B_, p_y, 0.0, E, NU)
    assert s["sigma_tt"] - s["sigma_rr"] == pytest.approx(2 * K_)


def test_hill_collapse_and_monotonic():
    h = hill_cylinder(0.0, A_, B_, K_, E, NU)
    p_c = h["p_c"]
    near = hill_cylinder(p_c * (1 - 1e-10), A_, B_, K_, E, NU)
    assert near["c"] == pytest.approx(B_, rel=1e-4)
    assert hill_cylinder(p_c, A_, B_, K_, E, NU)["c"] == pytest.approx(B_, rel=1e-12)
    p = np.linspace(0, p_c, 201)
    res = hill_cylinder(p, A_, B_, K_, E, NU)
    assert np.all(np.diff(res["u_b"]) > 0)
    assert np.all(np.diff(res["c"]) >= 0)
    # c solves the interface equation
    c = res["c"][p > h["p_y"]]
    pp = p[p > h["p_y"]]
    np.testing.assert_allclose(2 * K_ * np.log(c / A_) + K_ * (1 - c**2 / B_**2), pp, rtol=1e-12)
    np.testing.assert_allclose(res["u_b"][p > h["p_y"]], 2 * (1 - NU**2) * K_ * c**2 / (E * B_))
    with pytest.raises(ValueError):
        hill_cylinder(1.01 * p_c, A_, B_, K_, E, NU)
    with pytest.raises(ValueError):
        hill_cylinder([0.5 * p_c, 1.5 * p_c], A_, B_, K_, E, NU)


def test_hill_stress_field():
    p = 0.5 * (hill_cylinder(0.0, A_, B_, K_, E, NU)["p_y"] + 2 * K_ * np.log(B_ / A_))
    r = np.linspace(A_, B_, 2001)
    h = hill_cylinder(p, A_, B_, K_, E, NU, r=r)
    c = float(h["c"])
    assert A_ < c < B_
    srr, stt = h["sigma_rr"], h["sigma_tt"]
    assert srr[0] == pytest.approx(-p)
    assert abs(srr[-1]) < 1e-6 * K_
    # continuous radial stress, yield satisfied in the plastic zone, not exceeded outside
    assert np.max(np.abs(np.diff(srr))) < 1e-3 * K_
    np.testing.assert_allclose((stt - srr)[r < c], 2 * K_)
    assert np.all(stt - srr <= 2 * K_ * (1 + 1e-12))
    # equilibrium on both sides of the interface
    dr = 1e-6
    for rr in (1.1, 0.5 * (c + B_), 1.9):
        f = lambda x: hill_cylinder(p, A_, B_, K_, E, NU, r=x)
        d = (f(rr + dr)["sigma_rr"] - f(rr - dr)["sigma_rr"]) / (2 * dr)
        s = f(rr)
        assert abs(d + (s["sigma_rr"] - s["sigma_tt"]) / rr) < 1e-4 * K_
