"""A report's findings kept in the repository (``smfem report --full --publish docs/full-report``):
``tables/headline.csv``, ``tables/fronts.csv`` and ``tables/carried.csv`` as the run wrote them,
and ``run.json``: when, on what machine, how long, how many runs, and the largest run's memory.
Written by the command only, so that what README quotes from it can be made again."""

from __future__ import annotations

import json
import os
import platform
import shutil
import time
from pathlib import Path

import pandas as pd

#: the tables a published report keeps
PUBLISHED = ("headline", "fronts", "carried")


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


def publish(report, directory: Path, settings: str, workers: int, scheduler: str | None) -> dict:
    """Copy the report's :data:`PUBLISHED` tables into ``directory/tables`` and write
    ``directory/run.json``; returns what run.json says."""
    tables = Path(directory) / "tables"
    tables.mkdir(parents=True, exist_ok=True)
    for name in PUBLISHED:
        shutil.copyfile(report.out / "tables" / f"{name}.csv", tables / f"{name}.csv")
    runs = report.tables["runs"]
    memory = pd.to_numeric(runs.get("peak_memory_mb", pd.Series(dtype=float)), errors="coerce")
    largest = runs.loc[memory.idxmax()] if memory.notna().any() else None
    made = {
        "command": f"smfem report --{settings}" + (f" --scheduler {scheduler}" if scheduler else f" --workers {workers}"),
        "finished": time.strftime("%Y-%m-%d %H:%M:%S %Z"),
        "wall_time_s": round(report.wall_time_s, 1),
        "runs_executed": len(report.study.executed),
        "runs_cached": report.study.cached,
        "cpu_time_s_of_runs": round(float(pd.to_numeric(runs.cpu_time_s, errors="coerce").sum()), 1),
        "peak_memory_mb": None if largest is None else round(float(largest.peak_memory_mb), 1),
        "peak_memory_run": None if largest is None else f"{largest.case} {largest.solver} {largest.level}",
        "machine": {"cpu": _cpu_model(), "cpus": os.cpu_count(), "memory_gb": _memory_gb(),
                    "system": platform.platform(), "python": platform.python_version()},
    }
    (Path(directory) / "run.json").write_text(json.dumps(made, indent=2) + "\n")
    return made
