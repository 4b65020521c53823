"""A report's findings kept in the repository (``smfem report --full --publish docs/full-report``):
``tables/headline.csv``, ``tables/fronts.csv``, ``tables/carried.csv`` and ``tables/timing.csv`` as the
run wrote them, ``run.json`` (when, on what machine, how long, how many runs, the largest run's
memory), and the page made of them: ``README.md`` (the verdict, the headline and where each carried series
stopped) with ``work-precision.png`` (the paper's five scenes' fronts). Written by the command
only, so that what README quotes from it can be made again; ``python -m reports.publish DIR``
makes the page again from DIR's tables (what ``--publish`` does after copying them)."""

from __future__ import annotations

import json
import os
import platform
import shutil
import time
from pathlib import Path

import pandas as pd

from smfem.runs.figures import save, subplots
from smfem.runs.registry import REF3D, lookup
from smfem.studies import provenance
from smfem.studies.cache import made_of

from .figures import _log_axes
from .verdict import names_an_engine, summary_table, verdict

#: the tables a published report keeps
PUBLISHED = ("headline", "fronts", "carried", "timing", "timing_repeats")


#: what makes a published report: its runs' sources and the pages' writer (not the files it
#: publishes, which it has changed by the time it names its commit)
REPORT_SOURCES = (*provenance.SOURCES, "reports")


def _cpu_model() -> str:
    try:
        line = next(x for x in Path("/proc/cpuinfo").read_text().splitlines() if x.startswith("model name"))
        return line.split(":", 1)[1].strip()
    except (OSError, StopIteration):
        return platform.processor() or "unknown"


def _memory_gb() -> float | None:
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 1e9
    except (ValueError, OSError, AttributeError):
        return None


def made_here(study) -> dict:
    """What the distinct stored runs ``study`` read (series, same-dt references, fields, truth runs,
    error estimates) record of their making: ``runs_stored``, ``runs_made_from_these_sources``
    (a commit whose sources of that run, :func:`smfem.studies.provenance.sources_of` its solver's
    packages, are this checkout's: :func:`smfem.studies.provenance.same_sources`),
    and ``runs_made_from`` / ``runs_made_until``, the first and last time one was made (a report
    made in two passes spans both, with the pause between them)."""
    runs = {run.path: run for case in study.cases for run in case.all_runs() if run.path is not None}
    made = {path: made_of(run) for path, run in runs.items()}
    times = sorted(m["at"] for m in made.values() if m.get("at"))
    mine = sum(provenance.same_sources(made[path].get("commit"), provenance.sources_of(lookup(run.job.solver).packages))
               for path, run in runs.items())
    return {"runs_stored": len(runs), "runs_made_from_these_sources": mine,
            "runs_made_from": times[0] if times else None, "runs_made_until": times[-1] if times else None}


def publish(report, directory: Path, settings: str, workers: int, scheduler: str | None) -> dict:
    """Copy the report's :data:`PUBLISHED` tables into ``directory/tables`` and write
    ``directory/run.json``; returns what run.json says."""
    tables = Path(directory) / "tables"
    tables.mkdir(parents=True, exist_ok=True)
    for name in PUBLISHED:
        if (report.out / "tables" / f"{name}.csv").exists():  # no timing_repeats.csv without a pass
            shutil.copyfile(report.out / "tables" / f"{name}.csv", tables / f"{name}.csv")
    runs = report.tables["runs"]
    memory = pd.to_numeric(runs.get("peak_memory_mb", pd.Series(dtype=float)), errors="coerce")
    largest = runs.loc[memory.idxmax()] if memory.notna().any() else None
    made = {
        "command": "smfem report" + (" --full" if settings == "full" else "")
                   + (f" --scheduler {scheduler}" if scheduler else f" --workers {workers}"),
        "finished": time.strftime("%Y-%m-%d %H:%M:%S %Z"),
        "wall_time_s": round(report.wall_time_s, 1),
        "runs_executed": len(report.study.executed),
        "runs_cached": report.study.cached,
        # a report made from nothing at a commit has every run made from its sources, by this pass
        # or by an earlier one into the same new cache (smfem.studies.provenance)
        "commit": provenance.commit(REPORT_SOURCES),
        **made_here(report.study),
        "cpu_time_s_of_runs": round(float(pd.to_numeric(runs.cpu_time_s, errors="coerce").sum()), 1),
        "peak_memory_mb": None if largest is None else round(float(largest.peak_memory_mb), 1),
        "peak_memory_run": None if largest is None else f"{largest.case} {largest.solver} {largest.level}",
        "machine": {"cpu": _cpu_model(), "cpus": os.cpu_count(), "memory_gb": _memory_gb(),
                    "system": platform.platform(), "python": platform.python_version()},
    }
    (Path(directory) / "run.json").write_text(json.dumps(made, indent=2) + "\n")
    page(Path(directory))
    return made


#: what the summary table's cells mean (README quotes the table with it)
SUMMARY_NOTE = ("SMFEM reaches the target with the cheaper of its two elements; a speed-up is the other solver's "
                "CPU time to the same target over SMFEM's, \"> x\" a bound where that solver's series ends above the "
                "target, \"-\" no run of it.")
#: beside it where a cell names the 3D engine it was (a report with both engines' series)
ENGINES_NOTE = (" Over 3D FEM a speed-up is over the cheaper of the 3D reference's implicit and explicit engines "
                "at the target, named in the cell.")
#: the scenes of the published figure: the paper's five
FIGURE_SCENES = ("dome", "thick_cylinder", "notched_cylinder", "notched_strip", "rod_impact")


def front_figure(fronts: pd.DataFrame, path: Path, scenes=FIGURE_SCENES) -> Path:
    """Each solver's work-precision front (total error against CPU time, log-log) on each of
    ``scenes``, one panel each, 1 % dashed; the fronts as ``tables/fronts.csv`` has them."""
    scenes = [s for s in scenes if s in set(fronts.case)]
    cols = 3
    rows = -(-(len(scenes) + 1) // cols)  # one cell more, for the legend
    fig, axes = subplots(rows, cols, figsize=(10.5, 3.2 * rows), layout="constrained")
    axes = list(axes.flat)
    shown = {}
    for ax, scene in zip(axes, scenes):
        on = fronts[(fronts.case == scene) & fronts.on_front.astype(bool) & (fronts.total > 0)]
        for solver, pts in on.groupby("solver", sort=False):
            entry = lookup(solver)
            pts = pts.sort_values("cpu_s")
            shown[solver] = ax.plot(pts.cpu_s, 100 * pts.total, **entry.style, label=entry.label)[0]
        ax.axhline(1.0, color="0.4", ls="--", lw=0.8)
        ax.set(title=scene.replace("_", " "), xlabel="CPU time, s", ylabel="total error, %")
        _log_axes(ax)
    for ax in axes[len(scenes):]:
        ax.axis("off")
    axes[len(scenes)].legend(shown.values(), [h.get_label() for h in shown.values()], loc="center", frameon=False,
                             title="each solver's front\n(dashed: 1 % total error)")
    return save(fig, path)


def _provenance(made: dict) -> str:
    """``'; N of its M stored runs made from the sources of commit C that decide them'``, from run.json ('' for one
    written before it said)."""
    if "commit" not in made:
        return ""
    if made["commit"] is None:
        return "; no commit recorded"
    commit = made["commit"][:12] + ("" if "+" not in made["commit"] else " with changes")
    span = f", from {made['runs_made_from']} to {made['runs_made_until']}" if made.get("runs_made_from") else ""
    return (f"; {made.get('runs_made_from_these_sources', 0)} of its {made.get('runs_stored', 0)} stored runs made from "
            f"the sources of commit {commit} that decide them{span}")


def _markdown(table: pd.DataFrame) -> str:
    cells = table.astype(object).where(table.notna(), "").astype(str)
    lines = ["| " + " | ".join(cells.columns) + " |", "|" + "---|" * len(cells.columns)]
    lines += ["| " + " | ".join(row) + " |" for row in cells.itertuples(index=False)]
    return "\n".join(lines)


def page(directory: Path) -> Path:
    """``directory/README.md`` and ``directory/work-precision.png`` from the published tables and
    run.json (nothing in them is typed by hand)."""
    tables = directory / "tables"
    head = pd.read_csv(tables / "headline.csv")
    made = json.loads((directory / "run.json").read_text())
    front_figure(pd.read_csv(tables / "fronts.csv"), directory / "work-precision.png")
    machine = made["machine"]
    text = [f"# {'The full report' if '--full' in made['command'] else 'The report'}'s findings", "",
            f"Written by `{made['command']} --publish {directory.as_posix()}` on {made['finished']}: "
            f"{made['runs_executed']} runs executed, {made['runs_cached']} from the run cache"
            f"{_provenance(made)}, "
            f"{made['wall_time_s']:.0f} s wall on {machine['cpus']} cores ({machine['cpu']}, "
            f"{machine['memory_gb']:.0f} GB); {made['cpu_time_s_of_runs']:.0f} CPU s in the runs, the largest run "
            f"{made['peak_memory_mb']:.0f} MB ({made['peak_memory_run']}). Errors are total errors (space, harmonics "
            "and time together) against each scene's stored truth: the largest relative max-norm error over the "
            "displacement and velocity probes.", "", "## Verdict", "", *summary_table(head), "",
            SUMMARY_NOTE + (ENGINES_NOTE if names_an_engine(head, REF3D) else ""), "",
            *[f"- {line}" for line in verdict(head)], "", "## Work precision", "",
            "![each solver's work-precision front on the paper's five scenes](work-precision.png)", "",
            "## Headline (`tables/headline.csv`)", "", _markdown(head)]
    if (tables / "carried.csv").exists():
        text += ["", "## Where each carried series stopped (`tables/carried.csv`)", "",
                 _markdown(pd.read_csv(tables / "carried.csv"))]
    path = directory / "README.md"
    path.write_text("\n".join(text) + "\n")
    return path


if __name__ == "__main__":
    import sys

    if len(sys.argv) != 2 or not (Path(sys.argv[1]) / "run.json").exists():
        sys.exit("usage: python -m reports.publish DIR (a directory written by smfem report --publish DIR)")
    print(page(Path(sys.argv[1])))
