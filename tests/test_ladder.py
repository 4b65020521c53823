"""Series carried to a target (smfem/studies/ladder.py): where a ladder stops and why."""

from __future__ import annotations

import os
from types import SimpleNamespace

import numpy as np
import pytest

from cases import get_case
from smfem.studies.cache import Run
from smfem.studies.executors import run_jobs
from smfem.studies.jobs import Job
from smfem.studies.ladder import Ladder, work
from smfem.studies.plan import REF3D, REF3D_EXPLICIT, SMFEM, CaseStudy, Series, Until, grid
from smfem.studies.study import job_of

BASE = {"t_end": 4e-5}
T = np.linspace(0.0, 4e-5, 9)
TRUTH = SimpleNamespace(t=T, values={"apex_uz": np.sin(1e5 * T)}, converged=lambda probe: True)


def _ladder(until: Until, solver: str = SMFEM, levels=None) -> Ladder:
    levels = levels or ({"refine": 1}, {"refine": 2}, {"refine": 4})
    study = CaseStudy("dome", (Series(solver, levels, until=until),), reference=None, base=BASE)
    return Ladder.make(study.series[0], "dome", BASE, TRUTH, job_of(study))


def _run(job, error: float, cpu: float, ok: bool = True) -> Run:
    """A finished run of ``job`` off the truth by ``error`` (relative max norm) in ``cpu`` s."""
    result = SimpleNamespace(t=T, history={"apex_uz": (1 + error) * TRUTH.values["apex_uz"]}) if ok else None
    return Run(job, "ok" if ok else "failed", "", None, result, {"cpu_time_s": cpu, "params": job.build().params})


def test_a_ladder_runs_one_level_after_another_and_stops_at_its_target():
    ladder = _ladder(Until(target=0.01, budget_s=100))
    first, second, third = ladder.jobs
    assert ladder.running == [first]
    assert ladder.after(first, _run(first, 0.05, 0.1)) == [second] and ladder.running == [first, second]
    assert ladder.after(first, _run(first, 0.05, 0.1)) == []  # not the last asked: asks nothing
    assert ladder.after(second, _run(second, 0.008, 0.4)) == []
    assert ladder.running == [first, second]
    assert ladder.outcome.startswith("reached 1 % at r2") and "0.8 %" in ladder.outcome
    assert third not in ladder.running


def test_a_ladder_stops_before_a_level_predicted_over_its_budget():
    ladder = _ladder(Until(target=0.01, budget_s=1.0))
    first, second, _ = ladder.jobs
    assert ladder.after(first, _run(first, 0.05, 0.2)) == [second]  # 4 x the cells: 0.8 s predicted
    assert ladder.after(second, _run(second, 0.03, 0.8)) == []  # 4 x again: 3.2 s, over 1 s
    assert "over the budget of 1 s" in ladder.outcome and "about 3.2 CPU s" in ladder.outcome


def test_a_ladder_goes_past_a_failed_run_and_says_when_it_ends_short_of_the_target():
    ladder = _ladder(Until(target=0.01, budget_s=100))
    first, second, third = ladder.jobs
    assert ladder.after(first, _run(first, 0.0, 0.1, ok=False)) == [second]
    assert ladder.after(second, _run(second, 0.05, 0.4)) == [third]
    assert ladder.after(third, _run(third, 0.02, 1.6)) == []
    assert ladder.outcome == "ladder ended at r4 H1 (2 %): not reached"


def test_the_predicted_work_grows_with_cells_steps_and_harmonics():
    dome = get_case("dome").params
    assert work({**dome, "refine": 2}, False) == pytest.approx(4 * work(dome, False))
    assert work({**dome, "refine": 2, "dim": 3}, False) == pytest.approx(8 * work({**dome, "dim": 3}, False))
    assert work({**dome, "dt": dome["dt"] / 2}, False) == pytest.approx(2 * work(dome, False))
    thick = get_case("thick_cylinder").params
    assert work({**thick, "harmonics": 2 * thick["harmonics"]}, True) == pytest.approx(2 * work(thick, True))
    # the 3D reference's ladder predicts with dim 3 (its name fixes it)
    three_d = _ladder(Until(), REF3D, grid("dome", ({"refine": 1},), (1, 2)))
    assert [p["dim"] for p in three_d.params] == [3, 3]


def test_an_explicit_ladder_predicts_its_courant_steps_too():
    """An explicit engine steps at its own Courant limit: the next mesh has as many more steps as
    it is finer, whatever the case's dt (its output interval): r1 -> r2 in 3D is 16 times the work."""
    dome = {**get_case("dome").params, "dim": 3}
    assert work({**dome, "refine": 2}, False, courant=True) == pytest.approx(16 * work(dome, False, courant=True))
    assert work({**dome, "coarsen": 2}, False, courant=True) == pytest.approx(work(dome, False, courant=True) / 16)
    ladder = _ladder(Until(target=0.01, budget_s=100.0), REF3D_EXPLICIT, ({"refine": 2}, {"refine": 1}))
    first, second = ladder.jobs
    assert dict(first.overrides)["refine"] == 1
    assert ladder.after(first, _run(first, 0.05, 7.0)) == []  # 16 x 7 s = 112 s: past the budget
    assert "about 112 CPU s" in ladder.outcome


def test_until_refuses_a_target_outside_0_1_or_no_budget():
    for bad in ({"target": 0}, {"target": 1.5}, {"budget_s": 0}):
        with pytest.raises(ValueError, match="carried to a target"):
            Until(**bad)


def test_local_workers_take_a_job_added_while_they_run():
    """What a carried series needs of the executor: a job appended to the queue while the
    workers run is run too (the dask executor: tests/test_report.py)."""
    queue = [Job.make("dome", SMFEM, {"t_end": 1e-5})]
    finished = []
    for job, outcome in run_jobs(queue, workers=1):
        finished.append((job, outcome.status))
        if len(queue) == 1:
            queue.append(Job.make("dome", SMFEM, {"t_end": 1e-5, "refine": 2}))
    assert finished == [(queue[0], "ok"), (queue[1], "ok")]


def test_a_ladder_climbs_in_the_order_of_predicted_work():
    dt = get_case("dome").dt
    ladder = _ladder(Until(), levels=grid("dome", ({"refine": 1}, {"refine": 2}), (1, 2, 8)))
    # r1 dt / 8 and r2 dt / 2 tie (8 units): the plan's order
    assert [(p["refine"], round(dt / p["dt"])) for p in ladder.params] == [(1, 1), (1, 2), (2, 1), (1, 8), (2, 2),
                                                                          (2, 8)]


def test_the_session_pool_is_replaced_after_a_worker_dies():
    """A worker process that died (killed, out of memory) breaks the pool kept between studies:
    the next study gets a new one instead of the broken pool's error."""
    from concurrent.futures.process import BrokenProcessPool

    from smfem.studies.executors import in_worker

    with pytest.raises(BrokenProcessPool):
        in_worker(os._exit, 1, workers=1).result()
    queue = [Job.make("dome", SMFEM, {"t_end": 1e-5})]
    assert [outcome.status for _, outcome in run_jobs(queue, workers=1)] == ["ok"]


def test_a_level_carries_a_solver_option_to_its_job_and_its_ladder_orders_by_it():
    """CalculiX's modal levels are meshes x modes: ``modes`` is the run's option, not the case's
    (its job's options, its label), and the ladder orders and predicts by it too."""
    from smfem.runs.registry import CALCULIX_MODAL

    levels = ({"refine": 2, "modes": 50}, {"refine": 1, "modes": 400}, {"refine": 1, "modes": 50})
    ladder = _ladder(Until(), CALCULIX_MODAL, levels)
    assert [(dict(j.overrides)["refine"], dict(j.options)) for j in ladder.jobs] == [
        (1, {"modes": 50}), (2, {"modes": 50}), (1, {"modes": 400})]
    assert "modes" not in ladder.jobs[0].resolved.params
    assert Run(ladder.jobs[1], "ok", "", None).label == "r2 modes 50"
    assert work(ladder.params[2], False) == pytest.approx(16 * work(ladder.params[1], False))


def test_a_3d_runs_size_counts_the_elements_round_its_ring_and_a_mirror_half():
    from reference_fem.mesh import N_THETA
    from smfem.studies.ladder import THETA_PER_REFINE, size

    assert THETA_PER_REFINE == N_THETA  # the reference's ring at refine 1
    assert size({"dim": 3, "refine": 2}, False) == size({"dim": 3, "refine": 2, "theta_elements": 2 * N_THETA}, False) == 8
    half = {"dim": 3, "mirror": True}
    assert size(half | {"theta_elements": 32}, False) == pytest.approx(4 / 3 * size(half | {"theta_elements": 24}, False))
    assert size(half | {"theta_elements": 32}, False) == pytest.approx(0.25)
    assert size({"refine": 2, "theta_elements": 32}, False) == 4  # 2D: no ring
