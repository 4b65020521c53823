"""cases.recorder.StepRecorder: what is due when, a failed step, the RunResult it makes."""

from types import SimpleNamespace

import numpy as np

from cases.recorder import StepRecorder
from cases.result import RunResult


def scene(n_steps=6, dt=0.1, zone_times=(0.2, 0.5)):
    return SimpleNamespace(dt=dt, n_steps=n_steps, references={"plastic_zone_times": zone_times})


def run(recorder, steps, fail_at=None):
    """Record step 0 and steps 1..``steps`` (row = [n, -n]), failing at ``fail_at``."""
    recorder.record(0, [0.0, 0.0])
    for n in range(1, steps + 1):
        if n == fail_at:
            recorder.fail(f"step {recorder.done} failed")
            return
        recorder.record(n, [n, -n], iterations=10 + n)


def test_frames_snapshots_and_progress_when_due():
    made, calls = [], []
    recorder = StepRecorder(scene(), ["a", "b"], every=2, progress=lambda n, total: calls.append((n, total)),
                            frame=lambda: made.append("frame") or len(made), snapshot=lambda t: ("zone", t))
    run(recorder, 6)
    assert [t for t, _ in recorder.frames] == [0.0, 0.2, 0.4, 0.6000000000000001]
    assert made == ["frame"] * 4  # made only at the frames due
    assert recorder.snapshots == [("zone", 0.2), ("zone", 0.5)]
    assert calls == [(n, 6) for n in range(1, 7)]  # not for step 0, the initial state


def test_nothing_made_unless_asked():
    never = lambda *_: (_ for _ in ()).throw(AssertionError("made a frame or snapshot not asked for"))
    recorder = StepRecorder(scene(), ["a", "b"], frame=never)  # every 0, no snapshot: none due
    run(recorder, 6)
    assert recorder.frames == [] and recorder.snapshots == []


def test_a_failed_step_keeps_the_rows_before_it():
    recorder = StepRecorder(scene(), ["a", "b"])
    run(recorder, 6, fail_at=4)
    recorder.fail("a later verdict")  # the first message stands
    result = recorder.result(n_dof=7, cpu_time_s=1.5, mesh=None, info={"x": 1})
    assert isinstance(result, RunResult)
    assert not result.converged and result.message == "step 4 failed"
    assert np.array_equal(result.t, [0.0, 0.1, 0.2, 0.30000000000000004])
    assert np.array_equal(result.history["a"], [0, 1, 2, 3]) and np.array_equal(result.history["b"], [0, -1, -2, -3])
    assert result.iterations == [11, 12, 13]
    assert (result.n_dof, result.cpu_time_s, result.info) == (7, 1.5, {"x": 1})
    assert recorder.last_time == 3 * 0.1


def test_the_times_are_each_marchs_n_dt():
    """``RunResult.t`` is ``np.arange(done) * dt``: bit for bit the ``n * dt`` a march yields."""
    dt = 1e-5 / 3
    recorder = StepRecorder(scene(n_steps=1000, dt=dt), ["a"])
    for n in range(1001):
        recorder.record(n, [0.0], 1)
    assert recorder.result(n_dof=1).t.tolist() == [n * dt for n in range(1001)]


def test_an_empty_verdict_leaves_the_run_converged():
    recorder = StepRecorder(scene(), ["a", "b"])
    run(recorder, 6)
    recorder.fail("")
    result = recorder.result(n_dof=1)
    assert result.converged and result.message == "" and len(result.t) == 7
