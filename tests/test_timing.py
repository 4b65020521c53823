"""The timing pass (smfem/studies/timing.py, reports/timing.py): its rule, the order it times
runs in, and what a report's tables/timing.csv holds, after the build and after --retime.

Whether two passes agree within 10 % depends on the machine's load; what holds on any machine
is the structure: enough repeats, and each speed-up the ratio of its two minima.
"""

from __future__ import annotations

import re

import pandas as pd
import pytest

from reports.build import build
from reports.timing import COLUMNS
from smfem.cli import main
from smfem.runs.registry import headline_name, lookup
from smfem.studies.jobs import Job
from smfem.studies.metrics import TARGETS
from smfem.studies.plan import SMFEM
from smfem.studies.timing import TimingRule, retime
from test_report import TINY

MEASURED = re.compile(r"^[0-9.e+-]+x$")  # a speed-up both of whose sides reach the target


def test_a_run_is_done_at_three_repeats_and_two_cpu_seconds_and_a_long_one_once_or_twice():
    rule = TimingRule(budget_s=200.0)
    assert not rule.done([], 0.0)
    assert not rule.done([1.0, 1.0], 2.0) and rule.done([1.0, 1.0, 1.0], 3.0)
    assert not rule.done([0.1] * 19, 1.9) and rule.done([0.1] * 20, 2.0)
    assert not rule.done([61.0], 61.0) and rule.done([61.0, 60.5], 121.5)
    assert rule.done([61.0], 61.0 + 80.0)  # a second timing would pass the budget
    assert rule.batch([]) == 1 and rule.batch([5.0]) == 1
    assert rule.batch([0.01]) == 25  # a quarter of a CPU s per round trip, not 199 repeats at once
    assert rule.batch([0.2] * 9) == 1 and rule.batch([0.01] * 190) == 10


def test_a_scenes_runs_are_timed_by_turns_and_each_until_the_rule_holds():
    smfem, other, third = (Job("dome", s, ()) for s in ("smfem", "reference-2d", "reference-3d"))
    cost = {smfem: 0.5, other: 1.5, third: 70.0}
    order = []

    def run(job, repeats):
        order.extend([job.solver] * repeats)
        return [cost[job]] * repeats

    timings = retime([[smfem, other], [third]], TimingRule(budget_s=200.0), run=run, progress=False)
    assert order[:4] == ["smfem", "reference-2d", "smfem", "reference-2d"]
    assert [timings[j].repeats for j in (smfem, other, third)] == [4, 3, 2]
    timings = retime([[third]], TimingRule(budget_s=100.0), run=run, progress=False)
    assert timings[third].repeats == 1  # over a minute, and a second timing would pass the budget


def check_timing(tables: dict) -> None:
    """timing.csv's columns; every run under 10 s with at least 3 repeats; every measured speed-up
    of the headline the ratio of its two minima, each cost's CPU time its run's minimum."""
    timing, head = tables["timing"], tables["headline"]
    assert list(timing.columns) == COLUMNS and len(timing)
    assert (timing[timing.cpu_min_s < 10].repeats >= 3).all()
    assert ((timing.cpu_min_s <= timing.cpu_median_s) & (timing.cpu_median_s <= timing.cpu_max_s)).all()
    minimum = {(r.case, r.solver, r.target): r.cpu_min_s for r in timing.itertuples()}
    checked = 0
    for row in head.itertuples():
        for target in TARGETS:
            pct = f"{100 * target:g}pct"
            # a row of one solver's procedures (CalculiX's): the cheapest of their minima
            timed = [cpu for (case, solver, at), cpu in minimum.items()
                     if case == row.case and at == target and headline_name(solver) == row.solver]
            if timed:
                assert getattr(row, f"cpu_s_to_{pct}").startswith(f"{min(timed):.3g} (")
            speedup = str(getattr(row, f"smfem_speedup_{pct}"))
            if not MEASURED.match(speedup):
                continue
            mine = min(cpu for (case, solver, at), cpu in minimum.items()
                       if case == row.case and at == target and lookup(solver).family == SMFEM)
            assert float(speedup[:-1]) == pytest.approx(min(timed) / mine, rel=5e-3)
            assert getattr(row, f"smfem_speedup_{pct}_range")
            checked += 1
    assert checked


@pytest.fixture(scope="module")
def tiny_timed(tmp_path_factory):
    out = tmp_path_factory.mktemp("timed")
    return build(TINY, out, workers=2, progress=False, settings="tiny", document=False)


def test_the_report_times_its_decisive_runs_again_and_its_speedups_are_ratios_of_minima(tiny_timed):
    check_timing(tiny_timed.tables)
    written = pd.read_csv(tiny_timed.out / "tables" / "timing.csv")
    assert list(written.columns) == COLUMNS and len(written) == len(tiny_timed.tables["timing"])
    # the study's single shots stay where they were: runs.csv and fronts.csv
    fronts = tiny_timed.tables["fronts"]
    shots = {(r.case, r.solver, r.level): r.cpu_s for r in fronts.itertuples()}
    assert all(shots[r.case, r.solver, r.label] == pytest.approx(r.study_cpu_s)
               for r in tiny_timed.tables["timing"].itertuples())


def test_retime_runs_nothing_but_the_timing_pass_and_writes_timing_again(tiny_timed, tmp_path):
    again = build(TINY, tmp_path / "again", cache=tiny_timed.out / "runs", progress=False, settings="tiny",
                  document=False, retime=True)
    assert again.study.executed == []
    check_timing(again.tables)
    first, second = tiny_timed.tables["timing"], again.tables["timing"]
    assert first[["case", "solver", "target", "label"]].equals(second[["case", "solver", "target", "label"]])


def test_retime_without_the_reports_runs_is_a_usage_error(tmp_path, capsys):
    assert main(["report", "dome", "--retime", "--out", str(tmp_path / "none"), "--quiet"]) == 2
    assert "not in the run cache" in capsys.readouterr().err
    assert main(["report", "dome", "--retime", "--no-timing", "--out", str(tmp_path / "none")]) == 2
