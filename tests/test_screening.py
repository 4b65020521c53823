"""The iterations after a step's first visit only the points a change of the amplitudes may carry
past the yield surface (:mod:`smfem.screening`): the bound holds at every point, the law at a
subset is the law there, and a screened run has the histories of one that visits every point."""

from __future__ import annotations

import numpy as np
import pytest

from cases import get_case
from smfem import laws
from smfem.model import Model
from smfem.plasticity import von_mises
from smfem.sampling import SamplePoints
from smfem.screening import Screen
from smfem.solver import solve

from test_sampling_series import turned_cylinder


@pytest.mark.parametrize("case", [
    get_case("moving_load_notched", {"harmonics": 30}), get_case("notched_strip", {"harmonics": 30}),
    get_case("notched_cylinder", {"harmonics": 12}), turned_cylinder(8)],
    ids=["prism", "prism-mirrored", "ring-c", "ring-c-s"])
def test_the_bound_on_a_change_holds_at_every_point_and_stress_at_is_stress_there(case):
    """Random changes of the amplitudes, one concentrated in one mode: the von Mises stress of
    their stress at every point is within the bound of its section point, which is not idle (the
    largest point reaches a fifth of it at least once); at scattered points the restricted
    synthesis is the whole one's."""
    model = Model(case, nonlinear=True)
    points = SamplePoints(model, oversampling=1.0)
    screen = Screen(points)
    rng = np.random.default_rng(3)
    tightest = 0.0
    for trial in range(4):
        u = rng.normal(size=model.n_dof)
        if trial == 0:  # one mode only: the bound is its amplitude's, nearly reached
            lo, hi = model.offsets[1], model.offsets[2]
            u[:lo], u[hi:] = 0.0, 0.0
        stress = points.stress(u).reshape(6, -1)
        bound = screen.change_bound(points.series.coefficients(u))
        reached = von_mises(stress).reshape(len(bound), -1).max(axis=1)
        assert np.all(reached <= bound * (1 + 1e-12))
        tightest = max(tightest, float((reached / bound).max()))
        at = np.sort(rng.choice(stress.shape[1], size=stress.shape[1] // 40, replace=False))
        np.testing.assert_allclose(points.stress_at(u, at), stress[:, at], rtol=0, atol=1e-12 * np.abs(stress).max())
    assert tightest > 0.2
    room = np.zeros(int(np.prod(points.point_shape[1:])))
    coefficients = points.series.coefficients(u)
    assert len(screen.at_risk(coefficients, room)) == len(room)  # no headroom: every point
    far = np.full_like(room, 2 * screen.change_bound(coefficients).max())
    assert len(screen.at_risk(coefficients, far)) == 0 and len(points.stress_at(u, np.zeros(0, int))[0]) == 0


def test_the_von_mises_law_at_some_points_is_the_law_there():
    """Trial stresses about the yield stress at 200 points of a section of two materials (per
    point constants, one with hardening): the law at 40 of them gives their stresses, plastic
    strain and yielding points (among all) as the law over all points does."""
    case = get_case("layered_cylinder", {"plastic": True})
    n = 200
    index = np.arange(n) % len(case.materials)
    law = laws.for_points(case.materials, index, np.linspace(0.5, 1.0, n))
    rng = np.random.default_rng(5)
    state = law.initial_state(n)
    trial = rng.normal(size=(6, n)) * np.max(law.sigma_y0) * 0.7
    points = np.sort(rng.choice(n, size=40, replace=False))
    sigma, whole = law.stress(trial, state)
    some, part = law.stress_at(trial[:, points], state, points)
    assert 0 < len(part.yielding) < len(points)
    np.testing.assert_array_equal(part.yielding, np.intersect1d(whole.yielding, points))
    np.testing.assert_allclose(some, sigma[:, points], rtol=1e-15)
    np.testing.assert_allclose(part.alpha[points], whole.alpha[points], rtol=1e-15)
    assert not np.any(np.delete(part.alpha, points))
    headroom = law.headroom(trial, state)
    assert np.array_equal(np.flatnonzero(headroom < 0), whole.yielding)


@pytest.mark.parametrize("name, params, visited", [
    ("moving_load_notched", {"harmonics": 60}, 0.02),  # a few points about the load's path
    ("notched_cylinder", {"harmonics": 20, "t_end": 8e-3}, 0.2)])
def test_screened_iterations_have_the_histories_of_visiting_every_point(monkeypatch, name, params, visited):
    """The same iterations and histories within 1e-9 of each probe's largest value (the trials
    are the same sums in another order), the plastic strain probes' kept up at each step's
    yielding points as made whole; the screen leaves most points out of the iterations after a
    step's first (its share visited at most ``visited``, on average)."""
    case = get_case(name, params)
    shares = []
    at_risk = Screen.at_risk

    def counted(self, coefficients, room):
        out = at_risk(self, coefficients, room)
        shares.append(len(out) / len(room))
        return out

    monkeypatch.setattr(Screen, "at_risk", counted)
    screened = solve(case, with_fields=False)
    assert shares and np.mean(shares) <= visited
    monkeypatch.setattr("smfem.iterative.SCREEN_SHARE", -1.0)  # every point, every iteration
    monkeypatch.delattr(laws.VonMises, "equivalent_plastic_strain_at")  # the probes' plastic strain made whole
    whole = solve(case, with_fields=False)
    assert screened.iterations == whole.iterations
    assert max(np.abs(h).max() for n, h in whole.history.items() if n.startswith("peps")) > 0
    for probe, h in whole.history.items():
        assert np.abs(screened.history[probe] - h).max() <= 1e-9 * np.abs(h).max(), probe
