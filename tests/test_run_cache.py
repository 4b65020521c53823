"""What the run cache's code version covers (:func:`studies.cache.code_version`)."""

from studies.cache import PRESENTATION, source_files


def test_the_code_version_covers_the_stress_point_table_and_leaves_out_presentation():
    cases = {f"cases/{path.relative_to(root)}" for root, path in source_files("cases")}
    runs = {f"runs/{path.relative_to(root)}" for root, path in source_files("runs")}
    assert "cases/x3_points.csv" in cases  # SMFEM's stress points: a new table must rerun its runs
    assert "cases/x3_points.py" in cases and "runs/files.py" in runs
    assert not (cases | runs) & PRESENTATION
