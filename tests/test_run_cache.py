"""What the run cache's code version covers (:func:`smfem.studies.cache.code_version`)."""

from smfem.studies.cache import PRESENTATION, source_files


def test_the_code_version_covers_the_stress_point_table_and_leaves_out_presentation():
    cases = {f"cases/{path.relative_to(root)}" for root, path in source_files("cases")}
    runs = {f"smfem/runs/{path.relative_to(root)}" for root, path in source_files("smfem.runs")}
    assert "cases/x3_points.csv" in cases  # SMFEM's stress points: a new table must rerun its runs
    assert "cases/x3_points.py" in cases and "smfem/runs/files.py" in runs
    assert not (cases | runs) & PRESENTATION


def test_smfems_code_version_is_its_numerics_not_the_framework_beside_them():
    """The command line, the studies, the stored truths and the public API live in the
    ``smfem`` package too; editing them must not rerun SMFEM's cached runs."""
    numerics = {str(path.relative_to(root)) for root, path in source_files("smfem")}
    assert {"model.py", "solver.py", "woodbury.py"} <= numerics
    assert not [f for f in numerics if f.split("/")[0] in ("cli", "runs", "studies", "truths")
                or f in ("__init__.py", "__main__.py", "api.py")], numerics


def test_the_3d_references_count_round_and_mirror_half_are_in_a_runs_label():
    """Two runs of one series must never share a label (the analysis keys its errors by it)."""
    from smfem.runs.registry import REF3D
    from smfem.studies.cache import Run
    from smfem.studies.jobs import Job

    labels = [Run(Job.make("flywheel", REF3D, level), "ok", "", None).label
              for level in ({}, {"theta_elements": 16, "mirror": True}, {"theta_elements": 24, "mirror": True})]
    assert labels == ["r1", "r1 N16 half", "r1 N24 half"]


def test_two_runs_of_a_series_with_one_label_are_refused_not_confused():
    import pandas as pd
    import pytest

    from reports.analysis import _solver_summary
    from smfem.runs.registry import REF3D
    from smfem.studies.cache import Run
    from smfem.studies.jobs import Job

    params = {"refine": 1, "dt": 1e-5}
    runs = [Run(Job.make("flywheel", REF3D, {}), "ok", "", None, summary={"params": params, "cpu_time_s": c, "n_dof": 1})
            for c in (1.0, 2.0)]
    with pytest.raises(ValueError, match="two runs are labelled 'r1'"):
        _solver_summary(REF3D, runs, pd.DataFrame(), 0.0, {})
