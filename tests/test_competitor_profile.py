"""benchmarks/competitor_profile.py (its table: benchmarks/README.md): the runs it takes from a
report's tables, and the split of a run's CPU into set-up, solves, the rest of the march and
output."""

from __future__ import annotations

import time
from pathlib import Path

import pandas as pd
import pytest

from cases import get_case
from smfem.runs.registry import lookup
from smfem.studies.jobs import Job
from test_benchmarks import load

BENCHMARK = load(Path(__file__).resolve().parents[1] / "benchmarks" / "competitor_profile.py")
COLUMNS = ("case", "solver", "level", "refine", "coarsen", "harmonics", "dt", "dim", "element", "time_scheme",
           "n_dof", "cpu_s", "total", "on_front", "truth_key")


def test_the_cheapest_run_within_the_target_is_taken_per_competitor(tmp_path):
    """Per scene and headline row: the cheapest run within 1 %, else within 5 %; CalculiX's
    procedures one competitor at its cheapest; SMFEM's series none; each run's job the plan's."""
    runs = [("dome", "smfem", "r1 H1", 0.01, 0.001),
            ("dome", "reference-2d", "r1", 0.1, 0.02), ("dome", "reference-2d", "r2", 0.3, 0.008),
            ("dome", "reference-2d", "r4", 0.9, 0.004),
            ("dome", "calculix", "r1", 8.0, 0.018), ("dome", "calculix-modal", "r1 modes 50", 0.3, 0.0146),
            ("dome", "calculix-modal", "r2 modes 50", 0.9, 0.0035),
            ("dome", "reference-3d", "r1", 100.0, 0.07),
            ("thick_cylinder", "reference-2d", "r1", 1.0, 0.03), ("thick_cylinder", "reference-2d", "r2", 3.0, 0.012)]
    pd.DataFrame([dict(dict.fromkeys(COLUMNS, ""), case=c, solver=s, level=lv, cpu_s=cpu, total=e)
                  for c, s, lv, cpu, e in runs]).to_csv(tmp_path / "fronts.csv", index=False)
    picks = {(p.case, p.competitor): p for p in BENCHMARK.picks(tmp_path)}
    assert set(picks) == {("dome", "reference-2d"), ("dome", "calculix"), ("dome", "reference-3d"),
                          ("thick_cylinder", "reference-2d")}
    ref, ccx = picks["dome", "reference-2d"], picks["dome", "calculix"]
    assert (ref.level, ref.target, ref.study_cpu) == ("r2", 0.01, 0.3)
    assert dict(ref.job.overrides) == {"refine": 2, "dim": 2}
    assert (ccx.solver, ccx.level, ccx.target) == ("calculix-modal", "r2 modes 50", 0.01)
    assert ccx.job.solver == "calculix-modal" and dict(ccx.job.options) == {"modes": 50}
    assert not picks["dome", "reference-3d"].reached and picks["dome", "reference-3d"].best == 0.07
    assert (picks["thick_cylinder", "reference-2d"].level, picks["thick_cylinder", "reference-2d"].target) == ("r1", 0.05)
    only = BENCHMARK.picks(tmp_path, scenes=["dome"], solvers=["calculix-modal"])
    assert [(p.case, p.competitor) for p in only] == [("dome", "calculix")]


@pytest.mark.parametrize("solver, parts", [("reference-2d", ("set-up/model", "solves/factorization",
                                                              "solves/triangular", "output/probes")),
                                            ("reference-explicit", ("set-up/critical step", "output/probes"))])
def test_a_runs_parts_sum_to_its_cpu(solver, parts):
    """The parts are the run's CPU from its call to its return, split as it went; the solver's
    own CPU (what a study counts: no mesh, no output after the march) is within them."""
    job = BENCHMARK.shortened(Job.make("dome", solver, {}), 40)
    start = time.process_time()
    profile = BENCHMARK.profile_reference(job)
    outside = time.process_time() - start
    assert set(parts) <= set(profile.parts)
    assert all(profile.group(g) > 0 for g in ("set-up", "march", "output"))
    assert (profile.group("solves") > 0) == (solver == "reference-2d")
    assert profile.counted < profile.total <= outside < profile.total + 0.02 + 0.05 * outside


@pytest.mark.skipif(not lookup("calculix").installed(), reason="ccx is not installed")
def test_calculix_is_split_outside_ccx_and_its_factorizations_counted():
    """Deck, ccx (its set-up from a run of two output intervals) and the .frd read; implicit *DYNAMIC
    factorizes the mass once and the step matrix twice an increment (ccx 2.20's design)."""
    job = BENCHMARK.shortened(Job.make("dome", "calculix", {}), 4)
    profile = BENCHMARK.profile_calculix(job)
    assert set(profile.parts) == {"set-up/deck", "set-up/ccx", "march/ccx", "output/read .frd"}
    assert profile.group("set-up") + profile.group("march") >= profile.counted
    assert any(note.startswith("9 factorizations") for note in profile.notes), profile.notes
    assert get_case("dome").dt * 4 == pytest.approx(job.build().t_end)
