"""Reference FEM, transient runs: 2D against 3D, the dome against Bathe's curve, plasticity."""

from __future__ import annotations

import numpy as np
import pytest

from cases import get_case
from cases.result import RunResult
from reference_fem import solve
from reference_fem import equilibrium


def max_norm_error(a: np.ndarray, b: np.ndarray) -> float:
    """max |a - b| / max |b| over the window."""
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def extremum(result: RunResult, name: str, window, kind: str) -> tuple[float, float]:
    """(time, value) of the min or max of probe ``name`` inside the time ``window`` (s)."""
    inside = (result.t >= window[0]) & (result.t <= window[1])
    values = result.history[name][inside]
    k = np.argmin(values) if kind == "min" else np.argmax(values)
    return float(result.t[inside][k]), float(values[k])


@pytest.fixture(scope="module")
def cylinder_2d():
    return solve(get_case("thick_cylinder"))


@pytest.fixture(scope="module")
def cylinder_3d():
    return solve(get_case("thick_cylinder", {"dim": 3}))


@pytest.fixture(scope="module")
def dome_2d():
    return solve(get_case("dome"))


@pytest.fixture(scope="module")
def cylinder_plastic():
    return solve(get_case("thick_cylinder", {"plastic": True}))


def test_result_layout(cylinder_2d, cylinder_plastic):
    case = get_case("thick_cylinder")
    for res, plastic in ((cylinder_2d, False), (cylinder_plastic, True)):
        names = [p.name for p in get_case("thick_cylinder", {"plastic": plastic}).probes]
        assert list(res.history) == names
        assert res.t.shape == (case.n_steps + 1,) and res.t[0] == 0.0
        assert res.t[-1] == pytest.approx(case.t_end)
        assert all(v.shape == res.t.shape and v[0] == 0.0 for v in res.history.values())
        assert len(res.iterations) == case.n_steps
        assert res.converged and res.message == ""
        assert res.cpu_time_s > 0 and res.n_dof > 0
        assert res.mesh.point_data["displacement"].shape == (len(res.mesh.points), 3)
        assert ("peps" in res.mesh.cell_data) == plastic
        assert {"dim", "element", "n_elements", "intorder", "factorizations"} <= set(res.info)


def test_fields_file(tmp_path):
    """The final-time mesh writes and reads back as VTU (quadratic hexahedra, peps per cell)."""
    import meshio

    res = solve(get_case("notched_strip", {"dim": 3, "t_end": 10 * 3.2e-6}))
    res.mesh.write(tmp_path / "fields.vtu")
    back = meshio.read(tmp_path / "fields.vtu")
    assert back.cells[0].type == "hexahedron27" and len(back.cells[0]) == res.info["n_elements"]
    np.testing.assert_allclose(back.point_data["displacement"], res.mesh.point_data["displacement"])
    assert "peps" in back.cell_data


def test_progress_callback():
    calls = []
    solve(get_case("dome", {"t_end": 5e-5}), progress=lambda n, total: calls.append((n, total)))
    assert calls == [(n, 10) for n in range(1, 11)]


def test_elastic_steps_never_refactorize(cylinder_2d, cylinder_3d, dome_2d):
    for res in (cylinder_2d, cylinder_3d, dome_2d):
        assert res.info["factorizations"] == 1
        assert set(res.iterations) == {1}


def test_thick_cylinder_2d_against_3d(cylinder_2d, cylinder_3d):
    """Plane strain against one layer of hexahedra (half the radial elements).

    B_ut sits on the edge of a load patch, where the traction jumps: it converges slowest
    (the 2D value itself moves by 1.3 % from refine 1 to 3), hence 1 % there.
    """
    assert max_norm_error(cylinder_3d.history["A_ur"], cylinder_2d.history["A_ur"]) < 5e-3
    assert max_norm_error(cylinder_3d.history["C_ur"], cylinder_2d.history["C_ur"]) < 5e-3
    assert max_norm_error(cylinder_3d.history["B_ut"], cylinder_2d.history["B_ut"]) < 1e-2


def test_dome_against_published_extrema(dome_2d):
    """Bathe, Ramm & Wilson's apex history (read off their curve: 2 digits, +-0.01 ms).

    Measured at refine 1: first dip -0.0520 in at 0.170 ms, main -0.0889 at 0.355 ms,
    rebound +0.0497 at 0.570 ms (published -0.051 / 0.18, -0.090 / 0.36, +0.05 / 0.58).
    Tolerance: 5 % in value and 0.025 ms in time, the reading accuracy of a plotted curve.
    """
    ref = get_case("dome").references["apex_uz_extrema"]
    windows = [(0.1e-3, 0.25e-3), (0.25e-3, 0.5e-3), (0.45e-3, 0.7e-3)]
    for (t_pub, v_pub), kind, window in zip(ref["points"], ref["kinds"], windows):
        t, v = extremum(dome_2d, "apex_uz", window, kind)
        assert v == pytest.approx(v_pub, rel=0.05)
        assert abs(t - t_pub) < 0.025e-3


def test_dome_3d_against_2d(dome_2d):
    """The whole cap in 3D (O-grid, 2 layers of quadratic hexahedra) against the axisymmetric run."""
    res = solve(get_case("dome", {"dim": 3}))
    for window, kind in [((0.25e-3, 0.5e-3), "min"), ((0.45e-3, 0.7e-3), "max")]:
        assert extremum(res, "apex_uz", window, kind)[1] == pytest.approx(
            extremum(dome_2d, "apex_uz", window, kind)[1], rel=0.03)


def test_plastic_iterations(cylinder_plastic):
    """Elastic steps take one iteration; plastic ones a few (paper: at most 5 at tol 1e-5)."""
    its = np.array(cylinder_plastic.iterations)
    first_plastic = int(np.argmax(its > 1))
    assert first_plastic > 0 and np.all(its[:first_plastic] == 1)
    assert its.max() <= 5
    # each non-final Newton iteration of a yielding step solves a new tangent, by CG on the one
    # elastic factorization (reference_fem.linalg): no other factorization
    assert cylinder_plastic.info["factorizations"] == 1 and cylinder_plastic.info["cg_fallbacks"] == 0
    assert cylinder_plastic.info["cg_iterations"] >= int(np.sum(its - 1))
    h = cylinder_plastic.history
    assert np.all(h["peps_max"] >= h["peps_A"]) and h["peps_max"].max() > 1e-3
    assert np.all(h["peps_max"][: first_plastic + 1] == 0.0)


def test_non_convergence_keeps_history(monkeypatch):
    monkeypatch.setattr(equilibrium, "MAX_ITERATIONS", 2)
    case = get_case("thick_cylinder", {"plastic": True, "tol": 1e-12})
    res = solve(case)
    assert not res.converged
    n = len(res.t)
    assert f"step {n} " in res.message and f"t = {n * case.dt:.6g} s" in res.message
    assert 1 < n < case.n_steps + 1 and len(res.iterations) == n - 1
    assert all(v.shape == res.t.shape for v in res.history.values())


@pytest.mark.slow
def test_thick_cylinder_convergence():
    """2D refine 1, 2 against 3: the radial displacements converge, each step at least 2x."""
    runs = [solve(get_case("thick_cylinder", {"refine": r})) for r in (1, 2, 3)]
    for name in ("A_ur", "C_ur", "B_ut"):
        e1, e2 = (max_norm_error(r.history[name], runs[-1].history[name]) for r in runs[:2])
        assert e2 < e1 / 2
    assert max_norm_error(runs[0].history["A_ur"], runs[-1].history["A_ur"]) < 5e-3


@pytest.mark.slow
@pytest.mark.parametrize("name", ["notched_cylinder", "notched_strip"])
def test_notched_cases_run_in_3d(name):
    """The plastic notched scenes in 3D (short window) agree with 2D to a few per cent."""
    overrides = {"t_end": 40 * get_case(name).dt}
    two, three = solve(get_case(name, overrides)), solve(get_case(name, dict(overrides, dim=3)))
    assert two.converged and three.converged
    first = get_case(name).probes[0].name
    assert max_norm_error(three.history[first], two.history[first]) < 0.05


@pytest.mark.slow
def test_thick_cylinder_2d_against_3d_within_half_a_percent_at_refine_2():
    """The issue's 0.5 % for every probe, B_ut included, once the 3D mesh resolves the patch
    edge: 3D refine 2 (15 x 128 x 1 hexahedra, ~48k dof, ~30 s) against 2D refine 2."""
    two = solve(get_case("thick_cylinder", {"refine": 2}))
    three = solve(get_case("thick_cylinder", {"refine": 2, "dim": 3}))
    for name in ("A_ur", "B_ut", "C_ur"):
        assert max_norm_error(three.history[name], two.history[name]) < 5e-3, name
