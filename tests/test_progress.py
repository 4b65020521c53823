"""Progress where the output is not a terminal: a line every 10 s and one at the end."""

from __future__ import annotations

import io

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


def test_the_time_left_counts_unknown_runs_at_the_mean_of_the_known_ones():
    from smfem.studies.study import time_left

    assert time_left({"a": 100.0, "b": 300.0, "c": None}, workers=2) == (100 + 300 + 200) / 2
    assert time_left({"a": None}, workers=2) is None and time_left({}, workers=2) is None


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
