"""Decoupled harmonics marched in batches (smfem/batched.py): the same run as one batch of all
of them, probes, field, frames and error alike, with the progress over the whole run."""

import numpy as np
import pytest

from cases import get_case, verification
from cases.geometry import PRISM, RING
from smfem import batched
from smfem.model import Model
from smfem.options import SolverOptions
from smfem.solver import solve
from smfem.strategy import Batched

#: a batch's memory so small that every batch takes one harmonic, and one that takes them all
ONE_EACH, ALL = SolverOptions(batch_memory_mb=1e-6), SolverOptions(batch_memory_mb=1e6)


def close(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal to 1e-10 of the larger's largest entry."""
    return np.abs(a - b).max() <= 1e-10 * np.abs(b).max()


@pytest.mark.parametrize("scheme", ["newmark", "gauss"])
def test_batches_of_one_harmonic_give_the_run_of_one_batch(scheme):
    """The flywheel's 9-node section, 3 harmonics, a tenth of the window, a frame every 25 steps."""
    case = get_case("flywheel", {"element": "quad9", "harmonics": 3, "t_end": 5e-4, "time_scheme": scheme})
    calls = []
    apart = solve(case, ONE_EACH, progress=lambda n, total: calls.append((n, total)), every=25)
    whole = solve(case, ALL, every=25)
    assert apart.info["batches"] == [1] * len(whole.info["harmonics_used"]) and whole.info["batches"] == [3]
    assert "in 3 batches of at most 1 harmonic " in apart.info["solve"]
    assert "in 1 batch of at most 3 harmonics " in whole.info["solve"]
    for name in whole.history:
        assert close(apart.history[name], whole.history[name]), name
    for (t, a), (s, b) in zip(apart.frames + [(0, apart.mesh)], whole.frames + [(0, whole.mesh)]):
        assert t == s
        for key in ("displacement", "velocity"):
            assert close(a.point_data[key], b.point_data[key]), (t, key)
        assert close(a.cell_data["stress"][0], b.cell_data["stress"][0]), t
    assert len(apart.frames) == case.n_steps // 25 + 1
    # the progress counts the whole run's steps once, whatever the batches
    steps = [n for n, _ in calls]
    assert steps == sorted(set(steps)) and steps[-1] == case.n_steps and {t for _, t in calls} == {case.n_steps}


@pytest.mark.parametrize("body", [PRISM, RING])
def test_timed_body_forces_and_tractions_give_the_whole_runs_probes_and_exact_error(body):
    """The manufactured motion with a material the same along x3: its harmonics are independent,
    loaded by force terms that vary in time."""
    case = verification.build(body, {"t_end": 0.05, "a": 0.0})
    apart, whole = solve(case, ONE_EACH), solve(case, ALL)
    assert len(apart.info["batches"]) == len(whole.info["harmonics_used"]) > 1
    for name in whole.history:
        assert close(apart.history[name], whole.history[name]), name
    assert apart.info["error_l2"] == pytest.approx(whole.info["error_l2"], rel=1e-10)
    assert apart.iterations == whole.iterations == [1] * case.n_steps


def test_a_harmonics_predicted_share_is_its_factors_and_stiffness():
    """The prediction scales the largest harmonic's bytes by the square of the unknowns: within
    10 % of each harmonic's own factors and stiffness on the flywheel, the axisymmetric one's
    two unknowns per node included."""
    case = get_case("flywheel", {"element": "quad9", "harmonics": 3, "time_scheme": "gauss"})
    model = Model(case, stiffness=False)
    make = lambda part: Batched.system(case, part)
    share = batched.shares(model, make)
    for i, predicted in enumerate(share):
        system = make(model.restricted([i]))
        K = system.K
        held = system.lu.nbytes + K.data.nbytes + K.indices.nbytes + K.indptr.nbytes
        assert predicted == pytest.approx(held, rel=0.1), i


def test_batches_take_consecutive_harmonics_within_the_budget_one_at_least():
    assert batched.batches(np.array([3.0, 3.0, 3.0, 10.0, 1.0]), 6.0) == [range(0, 2), range(2, 3), range(3, 4),
                                                                          range(4, 5)]
    assert batched.batches(np.ones(4), 100.0) == [range(0, 4)]


def test_only_independent_harmonics_are_batched():
    """Plasticity, a wall, cut-outs and an iteration matrix asked for take the other systems."""
    assert batched.decoupled(get_case("thick_cylinder"), SolverOptions())
    assert not batched.decoupled(get_case("thick_cylinder", {"plastic": True}), SolverOptions())
    assert not batched.decoupled(get_case("rod_impact"), SolverOptions())
    assert not batched.decoupled(get_case("notched_cylinder", {"plastic": False}), SolverOptions())
    assert not batched.decoupled(get_case("thick_cylinder"), SolverOptions(iteration_matrix="sor"))
