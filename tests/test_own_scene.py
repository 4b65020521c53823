"""A scene of one's own gets the built-in scenes' verification: ``smfem study my_scene.toml`` (its
series, a truth made for it, the work-precision tables) and ``smfem truth my_scene.toml``, with
runs cached by the file's contents."""

from __future__ import annotations

import hashlib
import json
import shutil
from dataclasses import replace
from pathlib import Path

import pandas as pd
import pytest

from cases import get_case
from cases.scene_file import Source
from reports.build import build
from reports.scene import scene
from reports.sections import ReportContext
from smfem.cli import main
from smfem.studies.cache import RunCache
from smfem.runs.registry import CALCULIX, CALCULIX_EXPLICIT, CALCULIX_MODAL, REF3D_EXPLICIT
from smfem.studies.jobs import NOT_AVAILABLE, execute
from smfem.studies.own_scene import FULL_MODES, study_of
from smfem.studies.plan import EXPLICIT_TRUTH, REF2D, REF3D, SMFEM, SMFEM_QUAD9, Series
from smfem.studies.study import job_of, run_study

from test_report import LIGHT_TIMING

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
#: the pipe's first 25 steps: seconds for the whole study
SHORT = {"t_end": 5e-5}


@pytest.fixture
def pipe(tmp_path) -> Path:
    """examples/pipe.toml copied where the test may edit it."""
    return Path(shutil.copy(EXAMPLES / "pipe.toml", tmp_path / "pipe.toml"))


def test_a_scene_file_is_studied_with_every_solver_against_a_truth_made_for_it(pipe, tmp_path):
    study = study_of(str(pipe), base=SHORT)
    assert study.truth.method == EXPLICIT_TRUTH and study.truth.refine == (1, 2, 4)  # elastic-plastic: not modal
    assert [s.solver for s in study.series] == [SMFEM, SMFEM_QUAD9, REF2D, REF3D]
    study = replace(study, series=study.series[:3])  # the 3D run: two thirds of the study's CPU time
    # one worker process throughout: the runs take tenths of a second, and two workers for the
    # study besides the timing pass's one were three processes spawned, most of this test's time
    report = build((study,), tmp_path / "study", workers=1, progress=False, document=False, timing=LIGHT_TIMING)
    head = pd.read_csv(tmp_path / "study" / "tables" / "headline.csv")
    assert set(head.case) == {"pipe"} and set(head.solver) == {SMFEM, SMFEM_QUAD9, REF2D}
    assert head.truth.str.startswith("reference-explicit").all() and (head.truth_uncertainty_pct > 0).all()
    errors = pd.read_csv(tmp_path / "study" / "tables" / "errors.csv")
    total = errors[errors.kind == "total"]
    assert set(total.solver) == set(head.solver) and (total.err_max > 0).all() and total.err_max.notna().all()
    assert (tmp_path / "study" / "figures" / "pipe-work-precision.png").exists()
    assert sorted(p.name for p in pipe.parent.iterdir()) == ["pipe.toml", "study"]  # nothing beside the scene
    assert report.study.executed and (tmp_path / "study" / "runs" / "pipe").is_dir()
    ctx = ReportContext(report.analyses, report.tables, {}, report.study, "quick", tmp_path / "study")
    section = scene(ctx, report.analyses[0])  # its section in the report names the file it came from
    assert section.blocks[0]["text"] == "a scene from the file pipe.toml"
    assert section.blocks[1]["text"].startswith("pipe: SMFEM reaches ")  # the verdict follows

    cache = RunCache(tmp_path / "study" / "runs")
    assert run_study((study,), cache, workers=1, progress=False).executed == []
    # the same name, another load: SMFEM's run at the scene's settings is the new scene's, not the cached one
    pipe.write_text(pipe.read_text().replace("q = 1e7", "q = 2e7"))
    alone = replace(study_of(str(pipe), base=SHORT), series=(Series(SMFEM, ({},)),), reference=None, truth=None,
                    estimated=())
    anew = RunCache(cache.root)  # a cache reads a job's key once: a study sees its files as they were at its start
    assert [job.solver for job in run_study((alone,), anew, workers=1, progress=False).executed] == [SMFEM]


def test_the_truth_command_takes_a_scene_file(pipe, tmp_path, capsys):
    out = tmp_path / "truth"
    # one worker: its three runs take a second, the processes' start most of the rest
    assert main(["truth", str(pipe), "--set", "t_end=5e-5", "--workers", "1", "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["name"].startswith("reference-explicit") and 0 < summary["uncertainty"]["inner_ur"] < 1
    assert "inner_ur" in pd.read_csv(out / "history.csv").columns


def test_a_missing_scene_file_is_a_clear_error(tmp_path, capsys):
    for command in (["study", str(tmp_path / "none.toml"), "--out", str(tmp_path / "s")],
                    ["truth", str(tmp_path / "none.toml"), "--out", str(tmp_path / "t")]):
        assert main(command) == 2
        err = capsys.readouterr().err
        assert "none.toml: cannot read the scene file" in err and "Traceback" not in err


def test_a_scene_files_digest_covers_its_text_and_the_mesh_it_reads():
    case = get_case(EXAMPLES / "flywheel.toml")
    (path, sha), = case.source.files
    assert Path(path).name == "flywheel.msh" and sha == hashlib.sha256(Path(path).read_bytes()).hexdigest()
    assert Source("a.toml", "x", ((path, "1"),)).digest != Source("a.toml", "x", ((path, "2"),)).digest
    assert Source("a.toml", "x").digest != Source("a.toml", "y").digest


def test_a_scenes_study_starts_from_its_own_mesh_and_keeps_3d_runs_few():
    """A scene at refine 2 is studied (and its truth made) from refine 2 up; a scene the 2D
    reference cannot run (the flywheel: its load is not axisymmetric) has its 3D reference at
    the scene's mesh as the same-dt reference, and no 3D error estimates (a 3D run's companions
    are 3D runs too)."""
    finer = study_of(str(EXAMPLES / "pipe.toml"), base={"refine": 2})
    assert finer.truth.refine == (2, 4, 8) and {level["refine"] for level in finer.series[0].levels} == {2, 4}
    wheel = study_of(str(EXAMPLES / "flywheel.toml"))
    assert [s.solver for s in wheel.series] == [SMFEM, SMFEM_QUAD9, REF3D]
    assert wheel.reference == (REF3D, {"refine": 1}) and wheel.estimated == (SMFEM,)


def test_a_scenes_full_study_has_every_competitor_at_its_fastest():
    """The full study of a scene file runs, as the built-in scenes' does, the 3D reference's
    explicit engine (the scene's mesh and twice it) and CalculiX's three procedures; where the
    scene is elasto-plastic the modal one is refused before any work, in one line the report keeps."""
    full = study_of(str(EXAMPLES / "pipe.toml"), full=True)
    assert [s.solver for s in full.series] == [SMFEM, SMFEM_QUAD9, REF2D, REF3D, REF3D_EXPLICIT, CALCULIX,
                                               CALCULIX_EXPLICIT, CALCULIX_MODAL]
    by_solver = {s.solver: s for s in full.series}
    assert [level["refine"] for level in by_solver[REF3D_EXPLICIT].levels] == [1, 2]
    assert [level["modes"] for level in by_solver[CALCULIX_MODAL].levels] == list(FULL_MODES)
    assert [s.solver for s in study_of(str(EXAMPLES / "pipe.toml")).series] == [SMFEM, SMFEM_QUAD9, REF2D, REF3D]
    plastic = study_of(str(EXAMPLES / "pipe.toml"), full=True, base={"plastic": True})
    refused = execute(job_of(plastic)(CALCULIX_MODAL, {"modes": FULL_MODES[0]}))
    assert refused.status == NOT_AVAILABLE and "plasticity" in refused.message and "\n" not in refused.message
