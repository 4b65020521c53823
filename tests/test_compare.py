"""``smfem compare``: both solvers' runs, the comparison table and the plastic zones side by side."""

import json

import numpy as np
import pandas as pd
import pytest
from PIL import Image

from smfem.runs import zones
from smfem.cli import main


def test_compare_writes_both_runs_the_table_and_zones_side_by_side(tmp_path, capsys):
    # the first two of the paper's zone times (1.4 and 2.28 ms)
    assert main(["compare", "thick_cylinder", "--set", "plastic=true", "--set", "t_end=2.4e-3",
                 "--out", str(tmp_path)]) == 0
    table = pd.read_csv(tmp_path / "comparison.csv")
    assert list(table.probe) == ["A_ur", "B_ut", "C_ur", "peps_A", "peps_max", "plastic_area@0.0014",
                                 "plastic_area@0.00228"]
    assert np.isfinite(table.relative_error).all()
    displacement = table[table.measure == "max-norm"]
    assert (displacement.relative_error < 0.05).all()  # the paper's mesh on both sides
    for solver in ("smfem", "reference"):
        assert (tmp_path / solver / "history.csv").exists() and (tmp_path / solver / "summary.json").exists()
        snaps = zones.load(tmp_path / solver / "plastic_zones.npz")
        assert [round(s.t, 6) for s in snaps] == [1.4e-3, 2.28e-3]
        history = pd.read_csv(tmp_path / solver / "history.csv")
        for snap in snaps:  # the figure names the largest point value: peps_max at that time
            peak = history.peps_max[np.isclose(history.t, snap.t, rtol=0, atol=1e-9)].item()
            assert snap.peak == pytest.approx(peak, rel=1e-6) and snap.peps.max() <= snap.peak
        assert (snaps[0].peps >= 1e-3).sum() == 0 < (snaps[1].peps >= 1e-3).sum()  # yielding starts between
    with Image.open(tmp_path / "plastic_zones.png") as im:
        width, height = im.size
    assert height > 0.8 * width  # two rows of panels: SMFEM above the reference
    out = capsys.readouterr().out
    assert "peps_max" in out
    cpu = {s: json.loads((tmp_path / s / "summary.json").read_text())["cpu_time_s"] for s in ("smfem", "reference")}
    assert f"SMFEM / reference = {cpu['smfem'] / cpu['reference']:.3g}" in out
