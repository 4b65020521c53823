"""Loads that vary in time (docs/scenes.md): amplitude tables on every load, pressures moving
along x3; read from scene files, refused in one line where wrong, and taken alike by SMFEM
and the reference FEM."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from cases import get_case
from cases.geometry import PRISM, RING, Amplitude, Pressure, interval_fourier
from smfem.cli import main
from smfem.runs.registry import solve
from tests.test_scene_file import EXAMPLES, USER_SCENE

TURNING = str(EXAMPLES / "turning_patches.toml")

#: the scene of one's own with its patch as a pulse, and moving
PULSE = USER_SCENE.replace('x3_intervals = [[0.2, 0.3]]', 'x3_intervals = [[0.2, 0.3]]\namplitude = [[0, 0], [2e-6, 1], [4e-6, 0]]')
MOVING = USER_SCENE.replace('x3_intervals = [[0.2, 0.3]]', 'x3_intervals = [[-0.1, 0.0]]\nspeed = 5e4')


def relative(a, b) -> float:
    return float(np.abs(a - b).max() / np.abs(b).max())


def test_an_amplitude_is_linear_between_its_points_and_held_outside():
    a = Amplitude(((1.0, 0.0), (2.0, 4.0), (4.0, 2.0)))
    assert a(0.0) == 0.0 and a(1.5) == 2.0 and a(3.0) == 3.0 and a(9.0) == 2.0
    assert np.array_equal(a(np.array([1.0, 2.0])), [0.0, 4.0])


@pytest.mark.parametrize("points,needle", [
    (((0.0, 1.0),), "at least two"),
    (((0.0, 1.0), (0.0, 2.0)), "increase strictly"),
    (((1.0, 1.0), (0.5, 2.0)), "increase strictly"),
    (((0.0, 1.0), (1.0, math.nan)), "finite"),
])
def test_a_bad_amplitude_is_refused(points, needle):
    with pytest.raises(ValueError, match=needle):
        Amplitude(points)


def test_a_moving_patch_covers_its_shifted_interval_clipped_to_the_prism():
    p = Pressure(1.0, "top", ((-0.03, 0.0),), speed=1000.0)
    assert p.intervals_at(0.0, PRISM, 0.3) == ()
    assert np.allclose(p.intervals_at(1e-5, PRISM, 0.3), ((0.0, 0.01),))
    assert np.allclose(p.intervals_at(1e-4, PRISM, 0.3), ((0.07, 0.1),))
    assert np.allclose(p.intervals_at(3.2e-4, PRISM, 0.3), ((0.29, 0.3),))
    assert p.intervals_at(4e-4, PRISM, 0.3) == ()
    assert p.times_of_change(PRISM, 0.3, 6e-4) == pytest.approx((3e-5, 3e-4, 3.3e-4))
    ring = Pressure(1.0, "outer", ((-0.5, 0.5),), speed=2.0)
    # a turn later it is where it started: the basis functions do not see the wrap
    moved = ring.intervals_at(math.pi, RING, 2 * math.pi)
    assert interval_fourier(moved, 3, "cos", RING) == pytest.approx(interval_fourier(ring.x3_intervals, 3, "cos", RING))


@pytest.mark.parametrize("old,new,needle", [
    ("amplitude = [[0, 0], [2e-6, 1], [4e-6, 0]]", "amplitude = [[0, 0]]", "load[1].amplitude"),
    ("amplitude = [[0, 0], [2e-6, 1], [4e-6, 0]]", "amplitude = [[0, 0], [2e-6, 1], [1e-6, 0]]", "increase strictly"),
    ("amplitude = [[0, 0], [2e-6, 1], [4e-6, 0]]", "amplitude = [[0, 0], [2e-6, inf]]", "not a number"),
    ("amplitude = [[0, 0], [2e-6, 1], [4e-6, 0]]", "amplitude = [0, 1]", "[t, factor] pairs"),
    ("[[support]]\n", "[[support]]\nspeed = 3.0\n", "support[1].speed: unknown key"),
    ("amplitude = [[0, 0], [2e-6, 1], [4e-6, 0]]", 'speed = "fast"', "load[1].speed"),
])
def test_mistakes_in_a_timed_load_exit_2_naming_the_key(tmp_path, capsys, old, new, needle):
    assert PULSE.count(old) == 1
    scene, out = tmp_path / "scene.toml", tmp_path / "out"
    scene.write_text(PULSE.replace(old, new))
    assert main(["run", str(scene), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith(f"smfem: error: {scene}: ") and needle in err, err
    assert not out.exists()


def test_a_single_fourier_term_cannot_move(tmp_path, capsys):
    scene, out = tmp_path / "scene.toml", tmp_path / "out"
    scene.write_text(MOVING.replace("x3_intervals = [[-0.1, 0.0]]", "mode = 1"))
    assert main(["run", str(scene), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "load[1].speed" in err and "cannot move" in err and not out.exists()


def test_a_moving_load_on_a_ring_cannot_be_declared_symmetric(tmp_path, capsys):
    text = (EXAMPLES / "layered_cylinder.toml").read_text()  # symmetric = true
    scene, out = tmp_path / "scene.toml", tmp_path / "out"
    scene.write_text(text.replace('edge = "outer"\n', 'edge = "outer"\nspeed = 100.0\n'))
    assert main(["run", str(scene), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "symmetric: true, but load[1] moves" in err and not out.exists()


def test_a_moving_load_the_axisymmetric_reference_cannot_take_is_refused_in_one_line(tmp_path, capsys):
    # the flywheel's 2D reference is axisymmetric: a patch turning round the axis needs dim=3
    case = get_case("flywheel", {"dim": 2})
    moving = replace(case, loads=(replace(case.loads[0], speed=10.0),), symmetric=False)
    from cases.params import UnsupportedCase

    with pytest.raises(UnsupportedCase, match="dim=3"):
        solve("reference", replace(moving, params={**moving.params, "t_end": moving.dt}))


def test_smfem_takes_loads_that_vary_in_time_with_contact():
    """SMFEM's contact system adds the timed terms to its load (a block pushed along a ground
    in ``tests/test_friction_block_pairs.py`` depends on it); here a pull on the rod's free
    end ramped on over 3 steps moves it off the wall."""
    case = get_case("rod_impact", {"t_end": 6e-6, "v0": 1e-9})
    pull = Pressure(-1e6, "free_end", ((0.0, 2 * math.pi),), amplitude=Amplitude(((0, 0), (3e-6, 1))))
    run = solve("smfem", replace(case, loads=(pull,)))
    assert run.converged, run.message
    assert run.history["rod_vz"][1] > run.history["rod_vz"][0]  # pulled away from the wall (+z)
    assert run.history["contact_p"][-1] == 0.0


def test_a_pulse_from_its_first_point_on_is_the_step():
    step = get_case("layered_cylinder", {"t_end": 4e-4})
    held = replace(step, loads=(replace(step.loads[0], amplitude=Amplitude(((0.0, 1.0), (1.0, 1.0)))),))
    for solver in ("smfem", "reference"):
        a, b = solve(solver, step), solve(solver, held)
        assert all(relative(b.history[k], a.history[k]) < 1e-12 for k in a.history), solver


def test_the_pulse_agrees_between_smfem_and_the_reference():
    """Same dt, so the difference is spatial: SMFEM's 20 harmonics and 4-node elements against the
    reference's quadratic plane model (measured 0.22-3.5 % at the defaults, B_ut the smallest
    probe; here 0.8 ms, the pulse and its first ringing)."""
    case = get_case("layered_cylinder_pulse", {"t_end": 8e-4})
    a, b = solve("smfem", case), solve("reference", case)
    errors = {k: relative(a.history[k], b.history[k]) for k in a.history}
    assert max(errors.values()) < 0.05 and errors["A_ur"] < 0.01, errors
    # the load is off after 0.6 ms and was zero at t = 0
    assert all(abs(b.history[k][0]) == 0 for k in b.history)


def test_the_moving_load_agrees_between_smfem_and_the_reference_and_moves():
    """The patch passes a quarter of the span at 0.075 ms and mid-span at 0.15 ms: each probe's
    deflection peaks after the patch reaches it, in both solvers (measured: 0.05 % apart on the
    peaks at the defaults)."""
    case = get_case("moving_load", {"t_end": 2.4e-4})
    a, b = solve("smfem", case), solve("reference", case)
    for k in ("mid_uz", "q_uz"):
        assert relative(a.history[k], b.history[k]) < 0.01, k
    t = b.t
    first = {k: t[np.argmax(np.abs(b.history[k]) > 0.2 * np.abs(b.history[k]).max())] for k in ("q_uz", "mid_uz")}
    assert first["q_uz"] < first["mid_uz"]


def test_the_notched_moving_load_yields_with_coupled_harmonics_in_both_solvers():
    """The patch crosses the notch (x3 0.145-0.155 m) at 0.15-0.19 ms: the notch's corners yield
    in SMFEM, whose harmonics the cut-out couples (one system of them all), and in the 2D
    reference (peak plastic strains 0.10 and 0.19 %: the corners' singular strain, mesh-bound).
    Their deflections differ by SMFEM's harmonics and element: 0.49 / 0.20 % to 0.24 ms, more
    later (over the whole 0.6 ms against the explicit reference at refine 4: SMFEM 3.2 %, the
    2D reference at refine 1 1.4 %; docs/scenes.md)."""
    case = get_case("moving_load_notched", {"t_end": 2.4e-4})
    a, b = solve("smfem", case), solve("reference", case)
    assert "coupled" in a.info["solve"] and len(a.info["harmonics_used"]) == case.harmonics
    for run in (a, b):
        assert run.converged and np.max(run.history["peps_max"]) > 2e-4
    for k in ("mid_uz", "q_uz"):
        assert relative(a.history[k], b.history[k]) < 0.02, k


def test_a_moving_load_on_a_ring_excites_both_families():
    """The thick cylinder's two patches turning: the sine family joins the cosine one, and the
    half-turn symmetry still keeps the odd harmonics out."""
    case = get_case("thick_cylinder", {"t_end": 2e-4, "harmonics": 8})
    turning = replace(case, loads=(replace(case.loads[0], speed=500.0),), symmetric=False)
    used, held = (solve("smfem", c).info["harmonics_used"] for c in (turning, case))
    assert {m[-1] for m in held} == {"c"} and {m[-1] for m in used} == {"c", "s"}
    assert all(int(m[:-1]) % 2 == 0 for m in used)


@pytest.mark.parametrize("dim", [2, 3])
def test_the_reference_integrates_a_partly_covered_facet_exactly(dim):
    """The moving patch's nodal forces have the covered area's resultant and its first moment
    along the span (x3 is in the quadratic elements' span), at times when its ends cut facets."""
    from reference_fem.frames import x3_of
    from reference_fem.model import Model
    from reference_fem.moving import MovingPressure

    case = get_case("moving_load", {"dim": dim})
    model = Model(case)
    unit = MovingPressure(model, case.loads[0])
    width = 1.0 if dim == 2 else case.section.s.span[1] - case.section.s.span[0]
    x3 = x3_of(case, model.rep, model.basis.doflocs[:, ::dim])
    vertical = dim - 1  # the height's mesh component: (span, height) in 2D, (span, width, height) in 3D
    for t in (1e-5, 1.234e-4, 3.17e-4):
        Q = unit(t)[vertical::dim]
        (a, b), = case.loads[0].intervals_at(t, case.body, case.length)
        assert Q.sum() == pytest.approx(-(b - a) * width, rel=1e-12)
        assert Q @ x3 == pytest.approx(-0.5 * (b * b - a * a) * width, rel=1e-12)


def _gauss_rule(fdim, lo, hi, along, points=4):
    """A Gauss rule on a facet's reference cell, ``[lo, hi]`` along coordinate ``along``."""
    g, w = np.polynomial.legendre.leggauss(points)
    s, ws = lo + (hi - lo) * 0.5 * (g + 1), 0.5 * (hi - lo) * w
    if fdim == 1:
        return s[None, :], ws
    a, b = np.meshgrid(s, 0.5 * (g + 1), indexing="ij")
    return np.stack([a.ravel(), b.ravel()] if along == 0 else [b.ravel(), a.ravel()]), np.outer(ws, 0.5 * w).ravel()


def _by_facet_basis(unit, t):
    """The moving load as integrated before it was tabulated: a facet basis of scikit-fem's vector
    element on each covered range's own Gauss rule (65 ms a step on the turning patches), the
    whole facets' together."""
    from skfem import ElementVector

    from reference_fem import ties

    model = unit.model
    element = ElementVector(model.element.elem)
    lo, hi = unit.coverage(t)
    whole = (lo == 0.0) & (hi == 1.0)
    groups = [(np.flatnonzero(whole & (unit.along == a)), 0.0, 1.0, a) for a in np.unique(unit.along)]
    groups += [([f], lo[f], hi[f], unit.along[f]) for f in np.flatnonzero((hi > lo) & ~whole)]
    Q = np.zeros(model.basis.N)
    for facets, a, b, along in groups:
        if len(facets) == 0:
            continue
        fb = ties.facet_basis(model.rmesh.mesh, element, facets=unit.facets[facets],
                              quadrature=_gauss_rule(unit.fdim, a, b, int(along)))
        n = np.asarray(fb.normals)
        local = -np.stack([np.einsum("dfq,dfq,fq->f", np.asarray(fb.basis[i][0]), n, fb.dx) for i in range(fb.Nbfun)])
        np.add.at(Q, fb.element_dofs.ravel(), local.ravel())
    return Q


@pytest.mark.parametrize("scene, dim", [("moving_load", 2), ("moving_load", 3), (TURNING, 2), (TURNING, 3)])
def test_the_tabulated_moving_load_is_the_gauss_rule_on_each_covered_range(scene, dim):
    """A facet's load from its tabulated antiderivative, whole or partly covered, equals the
    Gauss rule on the covered range (the integrand is a polynomial along x3), on a prism and a
    ring, in 2D and 3D, at times when the patches' ends cut facets."""
    from reference_fem.model import Model
    from reference_fem.moving import MovingPressure

    case = get_case(scene, {"dim": dim})
    model = Model(case)
    for load in case.loads:
        unit = MovingPressure(model, load)
        cut = 0
        for t in np.linspace(0.0, case.t_end, 4)[1:] * 0.987:
            lo, hi = unit.coverage(t)
            cut += int(((hi > lo) & ~((lo == 0) & (hi == 1))).sum())
            expected = _by_facet_basis(unit, t)
            assert np.abs(unit(t) - expected).max() <= 1e-13 * np.abs(expected).max()
        assert cut > 0


def test_a_truths_key_holds_the_loads_history_and_path():
    """The stored truths' keys (smfem.studies.stored) name a load's amplitude and speed; a step held in
    place keys as it did before loads had a history (the stored truths stand)."""
    from smfem.studies.stored import case_definition, key_of
    from smfem.studies.truth import plan_for

    step = get_case("layered_cylinder")
    plan = plan_for("layered_cylinder", {}, "full")
    definition = case_definition(step)
    assert "amplitude" not in definition["loads"][0] and "speed" not in definition["loads"][0]
    pulse = get_case("layered_cylinder_pulse")
    assert case_definition(pulse)["loads"][0]["amplitude"]["points"][1] == (2e-4, 1.0)
    faster = replace(pulse, loads=(replace(pulse.loads[0], speed=1.0),))
    keys = {key_of(c, plan) for c in (step, pulse, faster)}
    assert len(keys) == 3


def _turning(tmp_path):
    """SMFEM's run of examples/turning_patches.toml over its first 1.2 ms, converged (refine 4,
    80 harmonics), from the command line: its histories and summary.json's harmonics."""
    import json

    import pandas as pd

    from tests.test_scene_file import EXAMPLES

    scene, out = EXAMPLES / "turning_patches.toml", tmp_path / "out"
    settings = ["--set", "t_end=1.2e-3", "--set", "refine=4", "--set", "harmonics=80"]
    assert main(["run", str(scene), "--out", str(out), "--estimate", "off", *settings]) == 0
    return scene, pd.read_csv(out / "history.csv"), json.loads((out / "summary.json").read_text())["harmonics_used"]


def test_patches_turning_round_a_ring_hold_both_families_in_the_summary(tmp_path):
    *_, used = _turning(tmp_path)
    assert {m[-1] for m in used} == {"c", "s"} and {m[:-1] for m in used if m.endswith("s")} == {
        m[:-1] for m in used if m.endswith("c") and m != "0c"}


@pytest.mark.slow
def test_patches_turning_round_a_ring_agree_with_the_3d_reference(tmp_path):
    """The same run against the 3D reference at refine 2, same dt (a spatial difference, measured
    0.04 / 0.29 / 0.02 %; with 40 harmonics B_ut is 1.1 % off: the turning load needs more
    harmonics than the held one). 30-60 CPU s: benchmarks/turning_patches.py has the window."""
    scene, mine, _ = _turning(tmp_path)
    full = solve("reference", get_case(scene, {"t_end": 1.2e-3, "refine": 2, "dim": 3}))
    for probe in full.history:
        assert relative(mine[probe].to_numpy(), full.history[probe]) < 0.01, probe


def test_a_moving_load_the_solver_cannot_take_exits_2_writing_nothing(tmp_path, capsys):
    """The flywheel's patch turning round the axis: its 2D reference is axisymmetric, which has
    no theta to move along (the 3D model has)."""
    text = (EXAMPLES / "flywheel.toml").read_text()
    text = text.replace("symmetric = true", "symmetric = false").replace(
        'x3_intervals = [["-patch_deg deg", "patch_deg deg"]]', 'x3_intervals = [["-patch_deg deg", "patch_deg deg"]]\nspeed = 10.0')
    text = text.replace('file = "../cases/sections/flywheel.msh"', f'file = "{EXAMPLES.parent / "cases" / "sections" / "flywheel.msh"}"')
    scene, out = tmp_path / "scene.toml", tmp_path / "out"
    scene.write_text(text)
    code = main(["run", str(scene), "--solver", "reference", "--set", "dim=2", "--out", str(out), "--estimate", "off"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "dim=3" in err and "Traceback" not in err, err
    assert not out.exists()
