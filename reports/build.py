"""Build a study's outputs: tables, figures, and (for the report) index.html and report.pdf."""

from __future__ import annotations

import shutil
import time
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from smfem.runs import threads, zones
from smfem.runs.figures import plastic_zones
from smfem.runs.registry import lookup

from . import figures
from .analysis import CaseAnalysis, analyse
from smfem.studies.cache import RunCache
from smfem.studies.executors import in_worker
from .document import render_html, write_pdf
from .outline import build_sections
from .sections import ReportContext
from smfem.studies.study import StudyResult, run_study
from smfem.studies.timing import TimingRule
from .tables import effectivity_table, write_tables
from .host_gate import WAITS, HostGate
from .timing import time_headline
from .view3d import render_field
from . import verification
from .stability import WITH_STABILITY, stability_rows

TITLE = "SMFEM verification report"


@dataclass
class Report:
    out: Path
    study: StudyResult
    analyses: list[CaseAnalysis]
    tables: dict
    figures: dict
    wall_time_s: float


def case_figures(an: CaseAnalysis, out: Path, draw: bool = True) -> dict[str, str]:
    """Draw (or copy) the case's figures and fields files (the final field and its time series);
    paths relative to ``out``. ``draw=False``: only their names, the files left as an earlier
    build made them (``--retime``: no figure depends on the timing pass)."""
    name, made = an.case.name, {}
    (out / "figures").mkdir(parents=True, exist_ok=True)
    if not an.available:
        return made
    made["work_precision"] = f"figures/{name}-work-precision.png"
    made["spatial"] = f"figures/{name}-spatial.png"
    made["histories"] = f"figures/{name}-histories.png"
    if draw:
        figures.work_precision(an, out / made["work_precision"])
        figures.spatial_precision(an, out / made["spatial"])
        figures.histories(an, out / made["histories"])
    run = an.runs.fields
    if run is not None and run.path is not None:
        rows = _zone_rows(an)
        if rows:
            made["plastic_zones"] = f"figures/{name}-plastic-zones.png"
            if draw:
                plastic_zones(rows, out / made["plastic_zones"], f"{name}: plastic zones at the paper's times", an.case)
        if (run.path / "fields.vtu").exists():
            made["vtu"] = f"fields/{name}-smfem.vtu"
            made["field"] = f"figures/{name}-field.png"
            if draw:
                (out / "fields").mkdir(exist_ok=True)
                shutil.copyfile(run.path / "fields.vtu", out / made["vtu"])
                render_field(out / made["vtu"], out / made["field"], f"{name} (SMFEM)", an.case.unit_of("u"))
        if (run.path / "fields.pvd").exists():  # the time series: the collection and its frames
            made["pvd"] = f"fields/{name}-smfem-series/fields.pvd"
            if draw:
                series = out / "fields" / f"{name}-smfem-series"
                series.mkdir(parents=True, exist_ok=True)
                for frame in [run.path / "fields.pvd", *sorted(run.path.glob("fields_*.vtu"))]:
                    shutil.copyfile(frame, series / frame.name)
    return made


def _zone_rows(an: CaseAnalysis) -> dict[str, list[dict]]:
    """SMFEM's plastic zones (the fields run) beside the same-dt reference's, where they have them."""
    return {lookup(run.job.solver).label: zones.load(run.path / "plastic_zones.npz")
            for run in (an.runs.fields, an.runs.reference)
            if run is not None and run.path is not None and (run.path / "plastic_zones.npz").exists()}


def code_verification_table(cache_dir: Path, settings: str) -> None:
    """Make (or find) the cached code verification table of a ``settings`` report."""
    threads.pin()
    verification.cached(cache_dir, quick=settings != "full")


def stability_table(cache_dir: Path, settings: str) -> None:
    """Make (or find) the cached stability table."""
    threads.pin()
    stability_rows(cache_dir)


#: the report's tables that are not runs of the study, made beside its figures
SIDE_TABLES = (code_verification_table, stability_table)


def build(plan, out: Path, cache: Path | None = None, scheduler: str | None = None, workers: int = 2,
          progress: bool = True, settings: str = "quick", document: bool = True,
          timing: TimingRule | None = TimingRule(), retime: bool = False, host_waits: int | None = None) -> Report:
    """Run (or reuse) the plan's runs, time the decisive ones again (``timing``) and write
    ``tables/*.csv``, ``figures/``, ``fields/`` and, with ``document``, ``index.html`` and
    ``report.pdf`` into ``out``.

    Parameters
    ----------
    plan : case studies (:mod:`smfem.studies.plan`)
    out : output directory
    cache : run cache directory (default ``out/runs``)
    scheduler : dask.distributed scheduler address; None: ``workers`` local processes
    settings : the plan's name, shown in the report
    timing : the timing pass's rule (:mod:`reports.timing`); None: no pass, single-shot CPU times
    retime : redo only the timing pass on ``out``'s earlier build: every run from the cache
        (:class:`smfem.studies.study.NotInCache` otherwise), no figure drawn again; the tables
        and the document written anew
    host_waits : how many times a batch of the pass may wait for a quiet host
        (:class:`reports.host_gate.HostGate`); None: :data:`~reports.host_gate.WAITS` for a full
        report or a retime, none for a quick one, whose wall time is bounded (its probes are
        still recorded)
    """
    wall0 = time.perf_counter()
    out = Path(out)
    study = run_study(plan, RunCache(cache or out / "runs"), scheduler, workers, progress, cached_only=retime)
    # the code verification and stability tables (38 and 33 CPU s) in the two worker processes
    # while this one draws the figures (a retime finds them in the cache when the document asks)
    side = ([in_worker(table, out / "runs", settings, workers=max(workers, 1)) for table in SIDE_TABLES]
            if document and settings in WITH_STABILITY and not retime else [])
    analyses = [analyse(cr) for cr in study.cases]
    figs = {an.case.name: case_figures(an, out, draw=not retime) for an in analyses}
    overall = {}
    effectivity = effectivity_table(analyses)
    if effectivity.get("effectivity", pd.Series(dtype=float)).notna().any():
        overall["effectivity"] = "figures/effectivity.png"
        if not retime:
            figures.effectivity(effectivity, out / overall["effectivity"])
    for table in side:
        table.result()
    # after the study's runs and the side tables: the pass runs alone on the executor
    (out / "tables").mkdir(parents=True, exist_ok=True)
    waits = host_waits if host_waits is not None else (WAITS if settings == "full" or retime else 0)
    timed = (time_headline(analyses, timing, progress, log=out / "timing-pass.jsonl",
                           repeats=out / "tables" / "timing_repeats.csv", run=HostGate(waits=waits))
             if timing is not None else None)
    tables = write_tables(analyses, out / "tables", timed)
    if document:
        ctx = ReportContext(analyses, tables, figs, study, settings, out, overall)
        subtitle = (f"{settings} settings; cases: {', '.join(an.case.name for an in analyses)}; "
                    "built by: smfem report" + (" --retime" if retime else ""))
        html = render_html(build_sections(ctx), TITLE, subtitle)
        (out / "index.html").write_text(html, encoding="utf-8")
        write_pdf(html, out / "report.pdf", out)
    return Report(out, study, analyses, tables, figs, time.perf_counter() - wall0)
