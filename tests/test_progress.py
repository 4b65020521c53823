"""Progress where the output is not a terminal: a line every 10 s and one at the end."""

from __future__ import annotations

import io
import math

from smfem.runs.progress import INTERVAL, Progress


class _Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def test_lines_every_interval_and_at_the_end_when_not_a_terminal():
    out, clock = io.StringIO(), _Clock()
    with Progress(100, "study", "run", stream=out, clock=clock) as bar:
        for n in range(1, 101):
            clock.t = n * INTERVAL / 4  # four updates per interval
            bar.update(n, f"run {n}")
    lines = out.getvalue().splitlines()
    assert len(lines) == 25  # 24 while running (the last update is the end's), 1 at the end
    assert lines[0] == "study: 4/100 runs, 10 s (run 4)"
    assert lines[-1] == "study: 100/100 runs, 250 s (run 100)"
    assert "\r" not in out.getvalue()


def test_quiet_prints_nothing():
    out = io.StringIO()
    with Progress(3, "dome (smfem)", "step", enabled=False, stream=out) as bar:
        bar.update(3)
    assert out.getvalue() == ""


def test_an_unfinished_count_leaves_the_last_word_to_its_error():
    out, clock = io.StringIO(), _Clock()
    with Progress(600, "rod_impact (calculix)", "step", stream=out, clock=clock) as bar:
        bar.update(0)
    assert out.getvalue() == ""


def test_an_estimate_of_the_time_left_is_said_while_running_and_not_at_the_end():
    out, clock = io.StringIO(), _Clock()
    with Progress(3, "study", "run", stream=out, clock=clock) as bar:
        clock.t = INTERVAL
        bar.update(1, "run 1", left_s=1500.0)
        clock.t = 2 * INTERVAL
        bar.update(2, "run 2", left_s=None)  # nothing known: nothing said
        clock.t = 3 * INTERVAL
        bar.update(3, "run 3", left_s=10.0)
    assert out.getvalue().splitlines() == ["study: 1/3 runs, 10 s, about 25 min left (run 1)",
                                           "study: 2/3 runs, 20 s (run 2)", "study: 3/3 runs, 30 s (run 3)"]


def test_a_line_is_said_while_nothing_finishes_and_the_time_left_counts_down():
    """A run of ten minutes in a study: the beat says the line every interval without an
    update, the time left less the time since it was estimated, nothing once it has run out."""
    import time

    out, clock = io.StringIO(), _Clock()

    def wait_for(lines):
        for _ in range(500):
            if len(out.getvalue().splitlines()) >= lines:
                return
            time.sleep(0.002)

    with Progress(3, "study", "run", stream=out, clock=clock, beat=0.001) as bar:
        bar.update(1, "run 1", left_s=100.0)  # at 0 s: no line yet
        clock.t = INTERVAL + 30
        wait_for(1)
        clock.t = 200.0
        wait_for(2)
    assert out.getvalue().splitlines() == ["study: 1/3 runs, 40 s, about 60 s left (run 1)",
                                           "study: 1/3 runs, 200 s (run 1)"]


class _Earlier:
    """A run cache that knows the earlier wall times of some jobs."""

    def __init__(self, walls=None):
        self.walls = walls or {}

    def previous_wall(self, job):
        return self.walls.get(job)


def _finished(job, wall):
    from smfem.studies.cache import Run

    return Run(job, "ok", "", None, None, {"wall_time_s": wall})


def test_the_time_left_of_a_fresh_study_comes_from_its_finished_runs():
    """On an empty cache nothing is said until a run is in; then the same scene and solver's
    runs are predicted by their work (refine 2 is four times refine 1's cells: 4 ** 0.7 times
    its time, the exponent of fewer than three runs), another solver's at the median of the
    finished ones, and no estimate is shorter than the longest run left."""
    from smfem.studies.eta import DEFAULT_EXPONENT, TimeLeft
    from smfem.studies.jobs import Job

    r1, r2, r3 = (Job.make("dome", "smfem", {"refine": r}) for r in (1, 2, 3))
    ref = Job.make("dome", "reference-2d", {"refine": 1})
    left = TimeLeft(_Earlier(), workers=2)
    left.expect([r1, r2, r3, ref])
    assert left.seconds() is None
    left.finished(r1, _finished(r1, 10.0))
    expected = {r2: 10.0 * 4 ** DEFAULT_EXPONENT, r3: 10.0 * 9 ** DEFAULT_EXPONENT, ref: 10.0}
    assert math.isclose(left.seconds(), max(sum(expected.values()) / 2, expected[r3]))  # r3 alone is longer
    left.finished(r2, _finished(r2, 20.0))
    left.finished(ref, _finished(ref, 1.0))
    b = DEFAULT_EXPONENT  # two runs: the exponent is not fitted, the factor is their mean's
    factor = math.exp((math.log(10.0) + math.log(20.0 / 4 ** b)) / 2)
    assert math.isclose(left.seconds(), factor * 9 ** b)  # one run left: all of it, not half


def test_a_power_law_is_fitted_to_three_runs_or_more_and_earlier_wall_times_come_first():
    from smfem.studies.eta import TimeLeft, power_law
    from smfem.studies.jobs import Job

    a, b = power_law([(w, 3.0 * w ** 0.9) for w in (1.0, 4.0, 16.0)])
    assert math.isclose(b, 0.9) and math.isclose(math.exp(a), 3.0)
    assert power_law([(w, w ** 3) for w in (1.0, 4.0, 16.0)])[1] == 1.5  # bounded
    jobs = [Job.make("dome", "smfem", {"refine": r}) for r in (1, 2, 3)]
    left = TimeLeft(_Earlier({jobs[2]: 100.0}), workers=2)
    left.expect(jobs)
    assert left.seconds() == 150.0  # the others, never run, at the mean of the known: 300 s on two workers
    left.finished(jobs[0], _finished(jobs[0], 1.0))
    assert math.isclose(left.seconds(), max((100.0 + 4 ** 0.7) / 2, 100.0))  # the earlier wall time stands
def test_a_runs_earlier_wall_time_is_found_across_code_versions(tmp_path, monkeypatch):
    """A resumed or re-run report expects each run to take what it took last time, whatever
    code version made it; a job never run has no estimate."""
    import json

    from smfem.studies import cache as cache_module
    from smfem.studies.cache import RunCache
    from smfem.studies.jobs import Job

    job, other = Job.make("dome", "smfem", {"refine": 2}), Job.make("dome", "smfem", {"refine": 3})
    cache = RunCache(tmp_path)
    entry = cache.path(job)
    entry.mkdir(parents=True)
    key = cache_module.key_of(job)
    key["version"] = "an-older-version"
    (entry / "job.json").write_text(json.dumps({"key": key}, default=str))
    (entry / "summary.json").write_text(json.dumps({"wall_time_s": 12.5}))
    assert RunCache(tmp_path).previous_wall(job) == 12.5
    assert RunCache(tmp_path).previous_wall(other) is None
