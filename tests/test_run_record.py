"""One run record end to end: what a solver returns is what its files give back."""

from __future__ import annotations

import numpy as np

from cases import get_case
from smfem.runs.files import read_run, write_run
from smfem.runs.registry import solve


def test_a_written_run_reads_back_as_the_result_it_was_written_from(tmp_path):
    """A plastic SMFEM run with a time series and plastic zones: histories (to history.csv's 10
    digits), per-step iterations, facts, the last field, every frame and each zone snapshot."""
    case = get_case("thick_cylinder", {"plastic": True, "t_end": 2.5e-3})
    result = solve("smfem", case, fields=True, every=20)
    assert result.snapshots and len(result.frames) > 2 and max(result.iterations) > 1  # all parts are exercised
    write_run(tmp_path, case, "smfem", result, wall_time_s=1.0)
    back, summary = read_run(tmp_path)
    assert summary["case"] == "thick_cylinder"
    assert np.allclose(back.t, result.t, rtol=1e-9, atol=0)
    assert back.history.keys() == result.history.keys()
    for name, h in result.history.items():
        assert np.allclose(back.history[name], h, rtol=1e-9, atol=1e-12 * np.abs(h).max()), name
    assert back.iterations == list(result.iterations) and back.n_dof == result.n_dof
    assert (back.converged, back.message, back.cpu_time_s) == (result.converged, result.message, result.cpu_time_s)
    assert back.info["harmonics_used"] == result.info["harmonics_used"]
    assert back.info["solve"] == result.info["solve"]
    assert np.allclose(back.mesh.point_data["displacement"], result.mesh.point_data["displacement"])
    assert np.allclose([t for t, _ in back.frames], [t for t, _ in result.frames], rtol=1e-11, atol=0)
    last = back.frames[-1][1].point_data["displacement"]  # frames in single precision
    assert np.allclose(last, result.frames[-1][1].point_data["displacement"], rtol=1e-6, atol=1e-7 * np.abs(last).max())
    for a, b in zip(back.snapshots, result.snapshots, strict=True):
        assert a.t == b.t and a.peak == b.peak
        assert np.array_equal(a.poly, b.poly) and np.array_equal(a.peps, b.peps) and np.array_equal(a.solid, b.solid)
