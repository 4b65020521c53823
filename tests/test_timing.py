"""The timing pass (smfem/studies/timing.py, reports/timing.py): its rule and the order it times
runs in (what a report's tables/timing.csv holds, after the build and after --retime: in
tests/test_report.py, beside the tiny report they read).

Whether two passes agree within 10 % depends on the machine's load; what holds on any machine
is the structure: enough repeats, and each speed-up the ratio of its two minima.
"""

from __future__ import annotations

import json

from smfem.cli import main
from smfem.studies.jobs import Job
from smfem.studies.timing import Timing, TimingRule, retime


def test_a_run_is_done_at_three_repeats_and_two_cpu_seconds_and_a_long_one_once_or_twice():
    rule = TimingRule(budget_s=200.0, settle_s=None, sweeps=4)
    assert not rule.done([], 0.0)
    assert not rule.done([1.0, 1.0], 2.0) and rule.done([1.0, 1.0, 1.0], 3.0)
    assert not rule.done([0.1] * 19, 1.9) and rule.done([0.1] * 20, 2.0)
    assert not rule.done([61.0], 61.0) and rule.done([61.0, 60.5], 121.5)
    assert rule.done([61.0], 61.0 + 80.0)  # a second timing would pass the budget
    # the minimum must hold: a second repeat within 5 % of it, up to the most repeats or the budget
    assert not rule.done([1.0, 1.3, 1.4], 3.7) and rule.done([1.0, 1.3, 1.4, 1.04], 4.74)
    assert not rule.done([1.0] + [1.3] * 28, 37.4) and rule.done([1.0] + [1.3] * 29, 38.7)
    assert rule.done([1.0, 1.3, 1.4], 201.0)
    assert rule.batch([], 0) == 1 and rule.batch([5.0], 1) == 1
    # a 10 ms run wants 199 more: shared among the three sweeps left, all at once in the last
    assert rule.batch([0.01], 1) == 67 and rule.batch([0.01], 3) == 199 and rule.batch([0.01], 9) == 199
    assert rule.batch([0.2] * 9, 2) == 1 and rule.batch([0.01] * 190, 2) == 5


def test_a_full_passs_run_settles_over_thirty_cpu_seconds_or_thirty_repeats_whatever_the_budget():
    """A short run's least settles only over many repeats (on this host one repeat in six to ten
    lies within 5 % of it): a full pass and a retime time a run to 30 CPU s or 30 repeats, past a
    held minimum and a spent budget; a quick one stops at its floor, for its ten minutes."""
    full, quick = TimingRule.of(True, budget_s=200.0), TimingRule.of(False, budget_s=200.0)
    assert quick.done([0.5, 0.5, 0.5, 0.5], 2.0) and quick.batch([0.5], 1) == 1
    assert not full.done([0.5] * 29, 500.0) and full.done([0.5] * 30, 15.0)  # the most repeats
    assert not full.done([2.0] * 14, 500.0) and full.done([2.0] * 15, 30.0)  # 30 CPU s, held
    assert not full.done([20.0] * 9, 180.0) and full.done([20.0] * 10, 200.0)  # a dear run: ten repeats
    assert not full.done([2.0] + [3.0] * 15, 47.0) and full.done([2.0] + [3.0] * 15, 500.0)  # not held: the budget
    assert full.done([0.01] * 200, 2.0)  # the floor's 2 CPU s take past the most repeats
    # what it still wants, shared among the ten sweeps' nine left or seven: 29 repeats of a 0.5 s
    # run, 14 of 2 s, 9 of 20 s (one a sweep: ten moments of the host)
    assert full.batch([0.5], 1) == 4 and full.batch([0.5], 3) == 5 and full.batch([2.0], 3) == 2
    assert full.batch([20.0], 1) == 1 and full.batch([20.0] * 9, 9) == 1
    assert full.batch([0.01], 1) == 23  # the floor's 199 repeats, past the settling's 29


def test_a_scenes_runs_are_timed_by_turns_in_sweeps_over_every_scene_until_the_rule_holds():
    smfem, other, third = (Job("dome", s, ()) for s in ("smfem", "reference-2d", "reference-3d"))
    fast = Job("rod_impact", "smfem", ())
    cost = {smfem: 0.5, other: 1.5, third: 70.0, fast: 0.01}
    calls = []

    def run(job, repeats):
        calls.append((job, repeats))
        return [cost[job]] * repeats

    timings = retime([[smfem, other], [third], [fast]], TimingRule(budget_s=200.0), run=run, progress=False)
    # sweep 1 times each run once, scene by scene, the scene's runs by turns; sweep 2 comes back
    assert [job for job, _ in calls[:6]] == [smfem, other, third, fast, smfem, other]
    # to 30 repeats (0.5 s) or 30 CPU s (1.5 s), the floor's 2 CPU s (10 ms), a long run twice
    assert [timings[j].repeats for j in (smfem, other, third, fast)] == [30, 20, 2, 200]
    # the 10 ms run's repeats are spread over the ten sweeps, not taken in one go
    assert [n for job, n in calls if job is fast] == [1, 23] + [22] * 8
    timings = retime([[third]], TimingRule(budget_s=100.0), run=run, progress=False)
    assert timings[third].repeats == 1  # over a minute, and a second timing would pass the budget


def test_retime_without_the_reports_runs_is_a_usage_error(tmp_path, capsys):
    assert main(["report", "dome", "--retime", "--out", str(tmp_path / "none"), "--quiet"]) == 2
    assert "not in the run cache" in capsys.readouterr().err
    assert main(["report", "dome", "--retime", "--no-timing", "--out", str(tmp_path / "none")]) == 2


def test_the_quick_settings_keep_the_study_shot_of_a_dear_run():
    """A quick report times only the runs whose study shot took at most 10 s (the cheap side of
    its ratios); a dearer run's shot stands as zero repeats. A full one, and a retime, time every run."""
    quick, full = TimingRule.of(False), TimingRule.of(True)
    assert quick.kept(10.5) and not quick.kept(9.5) and not full.kept(1e6)
    assert not TimingRule.of(False, retime=True).kept(1e6)  # a retime times the dear runs too
    # a quick report's minimum need not hold (its ten minutes); a full one's and a retime's must
    assert TimingRule.of(False).done([1.0, 1.3, 1.4], 3.7)
    assert not TimingRule.of(True).done([1.0, 1.3, 1.4], 3.7) and not TimingRule.of(False, retime=True).done([1.0, 1.3, 1.4], 3.7)
    job = Job("dome", "reference-3d", ())
    kept = Timing(job, (30.9,), retimed=False)
    assert kept.repeats == 0 and kept.cpu_min == kept.cpu_max == 30.9
    assert Timing(job, (1.0, 0.9, 1.1)).repeats == 3


def test_the_quick_settings_time_only_the_runs_that_can_decide_their_cost():
    """A quick pass leaves out a decisive run whose study shot is over three times its rivals'
    cheapest at that target: SMFEM's elements rival each other, a competitor's engines and
    procedures each other; the 2D reference rivals nobody. A full pass and a retime leave out the
    same runs."""
    from reports.timing import contenders
    from smfem.studies.cache import Run

    def run(cpu):
        return Run(None, "ok", "", None, None, {"cpu_time_s": cpu})

    runs = {("smfem", 0.01): run(1.4), ("smfem-quad9", 0.01): run(8.8),  # quad9: 6.3 times, left out
            ("smfem", 0.05): run(0.9), ("smfem-quad9", 0.05): run(2.2),  # 2.4 times: timed
            ("reference-2d", 0.01): run(30.0),  # no rival, whatever its cost
            ("reference-3d", 0.01): run(5.0), ("reference-3d-explicit", 0.01): run(16.0),  # 3.2 times: out
            ("calculix", 0.05): run(50.0), ("calculix-modal", 0.05): run(6.0)}  # implicit out
    quick = contenders(runs, TimingRule.of(False).rivals)
    assert set(runs) - set(quick) == {("smfem-quad9", 0.01), ("reference-3d-explicit", 0.01), ("calculix", 0.05)}
    assert all(quick[key] is runs[key] for key in quick)
    assert contenders(runs, TimingRule.of(True).rivals) == quick == contenders(runs, TimingRule.of(False, retime=True).rivals)
    assert contenders(runs, None) == runs


def test_a_stopped_pass_resumes_from_its_log_and_a_log_of_another_boot_or_source_is_not_taken_up(
        tmp_path, monkeypatch):
    """A full report's pass outlasts a working session (reports.timing.PassLog): stopped, it
    replays what it logged and times only the rest, ending with the timings of a pass never
    stopped; its log is removed when it finishes."""
    import pytest

    from reports import timing

    monkeypatch.setattr(timing.provenance, "commit", lambda *paths: "abc")
    monkeypatch.setattr(timing.provenance, "same_sources", lambda made_by, *paths: made_by == timing.provenance.commit())
    monkeypatch.setattr(timing, "boot", lambda: "boot-1")
    jobs = [Job.make("dome", "smfem", {}), Job.make("dome", "reference-2d", {}), Job.make("rod_impact", "smfem", {})]
    cost = dict(zip(jobs, (0.5, 1.5, 0.2)))
    rule, calls = TimingRule(budget_s=200.0), []

    def run(job, repeats):  # times that differ from call to call, as a host's do
        calls.append(job)
        return [cost[job] * (1 + 0.01 * ((len(calls) + i) % 7)) for i in range(repeats)]

    whole = retime([jobs[:2], jobs[2:]], rule, run=run, progress=False)
    n = len(calls)

    class Stopped(Exception):
        pass

    def stops_after_four(job, repeats):
        if len(calls) == 4:
            raise Stopped
        return run(job, repeats)

    calls.clear()
    path = tmp_path / "timing-pass.jsonl"
    with pytest.raises(Stopped):
        retime([jobs[:2], jobs[2:]], rule, run=timing.PassLog(path, rule, stops_after_four), progress=False)
    log = timing.PassLog(path, rule, run)
    assert 4 <= log.resumed < sum(len(t.times) for t in whole.values())
    resumed = retime([jobs[:2], jobs[2:]], rule, run=log, progress=False)
    assert len(calls) == n  # four batches replayed, the rest timed
    assert {j: t.times for j, t in resumed.items()} == {j: t.times for j, t in whole.items()}
    log.finish()
    assert not path.exists()
    # another boot, another rule or other sources: the log is started anew
    for boot, other_rule, commit in (("boot-2", rule, "abc"), ("boot-1", TimingRule(budget_s=100.0), "abc"),
                                     ("boot-1", rule, "def")):
        calls.clear()
        with pytest.raises(Stopped):
            retime([jobs[:2], jobs[2:]], rule, run=timing.PassLog(path, rule, stops_after_four), progress=False)
        monkeypatch.setattr(timing, "boot", lambda boot=boot: boot)
        monkeypatch.setattr(timing.provenance, "commit", lambda *paths, commit=commit: commit)
        assert timing.PassLog(path, other_rule, run).resumed == 0
        monkeypatch.setattr(timing, "boot", lambda: "boot-1")
        monkeypatch.setattr(timing.provenance, "commit", lambda *paths: "abc")
    # nor is a log the timing module took otherwise (it is no run's source, but it takes the repeats)
    calls.clear()
    with pytest.raises(Stopped):
        retime([jobs[:2], jobs[2:]], rule, run=timing.PassLog(path, rule, stops_after_four), progress=False)
    lines = path.read_text().splitlines()
    assert timing.PassLog(path, rule, run).resumed > 0
    path.write_text("\n".join([json.dumps(dict(json.loads(lines[0]), timer="another")), *lines[1:]]) + "\n")
    assert timing.PassLog(path, rule, run).resumed == 0


def test_a_batch_waits_for_the_hosts_memory_speed_to_come_back_within_the_slack():
    """reports.host_gate.HostGate: a batch is timed once the memory probe is within the slack
    (25 %) of the best the pass has seen, after waiting out a slow spell (at most ``waits``
    times); a batch expected to be cheap is timed at once."""
    from reports.host_gate import HostGate, memory_probe

    probes, slept, ran = iter([1.0, 1.5, 1.3, 1.05, 2.0, 2.0, 2.0]), [], []
    gate = HostGate(run=lambda job, n: ran.append((job, n)) or [0.5] * n, waits=2, wait_s=20.0,
                    probe=lambda: next(probes), sleep=slept.append)
    assert gate("a", 3) == [0.5] * 3 and (gate.last_probe, gate.last_waits, slept) == (1.0, 0, [])
    assert gate("b", 1) == [0.5] and (gate.last_probe, gate.last_waits, slept) == (1.05, 2, [20.0, 20.0])
    # a spell longer than the waits: the batch is timed anyway, and its probe says so
    assert gate("c", 2) == [0.5] * 2 and (gate.last_probe, gate.last_waits) == (2.0, 2) and len(slept) == 4
    assert ran == [("a", 3), ("b", 1), ("c", 2)] and gate.best == 1.0
    # the pass's waiting budget spent, a slow host is timed at once
    spent = HostGate(run=lambda job, n: [0.5] * n, waits=6, wait_s=20.0, budget_s=50.0,
                     probe=iter([1.0] + [2.0] * 20).__next__, sleep=slept.append)
    spent("a", 1), spent("b", 1), spent("c", 1)
    assert (spent.waited_s, spent.last_waits) == (40.0, 0) and len(slept) == 6
    # a batch expected under worth_s (its study shot times its repeats) does not wait for a slow host
    cheap = HostGate(run=lambda job, n: [0.5] * n, waits=6, wait_s=20.0, worth_s=2.0,
                     probe=iter([1.0, 2.0, 2.0, 2.0, 1.0]).__next__, sleep=slept.append)
    cheap.expected = {"short": 0.5, "long": 1.5}
    slept.clear()
    cheap("short", 1), cheap("short", 3)
    assert (cheap.last_probe, cheap.last_waits, slept) == (2.0, 0, [])
    cheap("long", 2)  # 3 s expected: it waits out the slow probe
    assert (cheap.last_probe, cheap.last_waits, slept) == (1.0, 2, [20.0, 20.0])
    assert 0 < memory_probe(1) < 1.0  # the real probe: a stream through 64 MB and back
