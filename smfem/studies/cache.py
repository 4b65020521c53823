"""Finished runs on disk, keyed by case, resolved parameters, solver and code version.

A run's directory holds what ``smfem run`` writes (``history.csv``, ``summary.json``, maybe
``fields.vtu`` and ``plastic_zones.npz``) and ``job.json`` (the key's ingredients, the outcome
and each file's sha256). The code version is a hash of the sources a solver's results depend
on, so editing the reference solver does not throw away SMFEM runs, and the other way round.

Writes are atomic; reads are checked: an entry whose ``job.json`` does not parse, or whose
files are missing or differ from their checksums (a disk error, a hand edit, a copy cut
short), is never used. It is run again, with one line saying so.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import json
import os
import shutil
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from cases.result import RunResult
from smfem.runs.files import read_run
from smfem.runs.registry import lookup

from .jobs import FAILED, NOT_INSTALLED, Job, Outcome
from . import provenance

#: packages whose source decides every solver's results (each adds its own, :mod:`smfem.runs.registry`)
SHARED_SOURCES = ("cases", "smfem.runs")
#: modules of those packages that decide nothing in a run's results (they draw, report, measure
#: the memory, or read finished runs: the error estimate and the --tol search): editing them must
#: not send a report back to rerunning every solve
PRESENTATION = {f"smfem/runs/{m}.py" for m in ("figures", "progress", "memory", "estimate", "tolerance", "errors")}
#: the framework inside the ``smfem`` package, above its numerics (docs/architecture.md): none of
#: it decides SMFEM's results, so none of it is in SMFEM's code version (``smfem/runs`` is in
#: every solver's, as a shared source)
FRAMEWORK = ("smfem/__init__.py", "smfem/__main__.py", "smfem/api.py", "smfem/cli", "smfem/runs",
             "smfem/studies", "smfem/truths")


@functools.cache
def code_version(solver: str) -> str:
    """sha256 (16 hex digits) of the ``.py``, ``.csv`` and ``.msh`` files of the packages ``solver``
    depends on (``cases/x3_points.csv`` sets SMFEM's stress points: a new table reruns them)."""
    h = hashlib.sha256()
    for package in (*lookup(solver).packages, *SHARED_SOURCES):
        for root, path in source_files(package):
            h.update(str(path.relative_to(root)).encode())
            h.update(path.read_bytes())
    return h.hexdigest()[:16]


def source_files(package: str) -> list[tuple[Path, Path]]:
    """``(package root, file)`` of the files of ``package`` (dotted) that decide a run's results."""
    root = Path(importlib.util.find_spec(package).submodule_search_locations[0])
    name = package.replace(".", "/")
    above = [f for f in FRAMEWORK if not name.startswith(f)]  # a package's own framework parts are itself

    def decides(path: Path) -> bool:
        shown = f"{name}/{path.relative_to(root)}"
        return shown not in PRESENTATION and not any(shown == f or shown.startswith(f"{f}/") for f in above)

    return [(root, path) for path in sorted(p for p in root.rglob("*") if p.suffix in (".py", ".csv", ".msh"))
            if decides(path)]


def key_of(job: Job) -> dict:
    """What identifies a run: the resolved parameters, not the overrides that led to them (and
    a scene file's contents, :attr:`cases.scene_file.Source.digest`)."""
    case = job.build()
    key = {"case": job.case, "solver": job.solver, "params": case.params, "fields": job.fields,
           "version": code_version(job.solver)}
    if case.source is not None:  # a scene from a file: its text (and mesh) decide the run too
        key["scene"] = case.source.digest
    return {**key, "options": dict(job.options)} if job.options else key


@dataclass
class Run:
    """A finished (or refused) run as the report reads it: the :class:`RunResult` its solver
    returned, read back from the cache (:func:`smfem.runs.files.read_run`; the fields stay on disk at
    ``path``), and its summary.json."""

    job: Job
    status: str
    message: str
    path: Path | None
    result: RunResult | None = None
    summary: dict | None = None

    @functools.cached_property
    def history(self) -> pd.DataFrame | None:
        """``t`` and every probe, one row per time (None without a result)."""
        return None if self.result is None else pd.DataFrame({"t": self.result.t, **self.result.history})

    @property
    def label(self) -> str:
        """``r2 H40`` (refine, ``r1/2`` coarsened; harmonics where the solver has them), with ``dt`` when it is not
        the case's default, the parameters its solver fixes besides ``dim`` (``quad9``), a
        time scheme other than Newmark's (``gauss``) and the 3D reference's count round a ring
        and mirror half (``N16 half``): two runs of a series never share a label."""
        p = self.summary["params"] if self.summary else self.job.build().params
        default_dt = self.job.defaults["dt"]
        coarse = f"/{p['coarsen']}" if p.get("coarsen", 1) != 1 else ""  # r1/2: half the paper mesh
        text = f"r{p.get('refine', 1)}{coarse}" + (f" H{p.get('harmonics')}" if lookup(self.job.solver).harmonics else "")
        text += f" dt{p['dt']:g}" if p.get("dt", default_dt) != default_dt else ""
        text += "".join(f" {v}" for _, v in lookup(self.job.solver).fixes)  # quad9
        text += f" {p['time_scheme']}" if p.get("time_scheme", "newmark") != "newmark" else ""  # gauss
        text += f" N{p['theta_elements']}" if p.get("theta_elements") else ""  # elements round a 3D ring
        text += " half" if p.get("mirror") else ""
        # an option named by its key when it is a switch (bbar), by its value when a word (superlu)
        return text + "".join(f" {k}" if v is True else f" {v}" if isinstance(v, str) else f" {k} {v}"
                              for k, v in self.job.options)

    @property
    def usable(self) -> bool:
        """A history to compare (a run that stopped early still has its converged steps)."""
        return self.history is not None and len(self.history) > 1


def _without_version(key: dict) -> str:
    """A run's key as job.json stores it (JSON, values it cannot hold as text), sorted, without
    the code version: one run's identity across versions."""
    plain = json.loads(json.dumps(key, default=str))
    plain.pop("version", None)
    return json.dumps(plain, sort_keys=True)


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


class RunCache:
    """Directory ``root/CASE/SOLVER/KEY`` per run; ``warn`` takes the line that names a damaged
    entry (default: stderr)."""

    def __init__(self, root: Path, warn=None):
        self.root = Path(root)
        self.warn = warn or (lambda line: print(line, file=sys.stderr))
        self._paths: dict[Job, Path] = {}  # a job's key is made once (a study asks several times)
        self._earlier: dict[str, dict] | None = None  # earlier runs' records by key without version

    def path(self, job: Job) -> Path:
        if job not in self._paths:
            key = key_of(job)
            digest = hashlib.sha256(json.dumps(key, sort_keys=True, default=str).encode()).hexdigest()[:20]
            self._paths[job] = self.root / job.scene / job.solver / digest
        return self._paths[job]

    def load(self, job: Job) -> Run | None:
        """The stored run of ``job``, or None if it has not run with this code version or its
        entry is damaged (then said, and run again)."""
        path = self.path(job)
        if not (path / "job.json").exists():
            return None
        record, damage = _checked(path)
        if damage:
            self.warn(f"cache: {job.describe()}: {damage} ({path}); running it again")
            return None
        return _read(job, record["status"], record["message"], path)

    def previous_wall(self, job: Job) -> float | None:
        """The wall time (s) of the last run of ``job`` made by any code version (the cache keeps
        the runs of earlier versions beside the current ones), or None: what a study expects
        the run to take (:func:`smfem.studies.study.run_cached`'s estimate of the time left)."""
        return (self.previous(job) or {}).get("wall_time_s")

    def previous(self, job: Job) -> dict | None:
        """The record of the last run of ``job`` made by any code version (:meth:`earlier`), or None."""
        return self.earlier().get(_without_version(key_of(job)))

    def earlier(self) -> dict[str, dict]:
        """Every finished run on disk, of any code version, by its key without the version: its
        ``case``, ``solver``, ``params``, and from its summary.json ``wall_time_s``, ``n_dof`` and
        ``peak_memory_mb`` (None where the run did not record it); read once."""
        if self._earlier is None:
            self._earlier = {}
            for path in self.root.glob("*/*/*/job.json"):
                try:
                    key = json.loads(path.read_text())["key"]
                    summary = json.loads((path.parent / "summary.json").read_text())
                    record = {"case": key["case"], "solver": key["solver"], "params": key["params"],
                              "wall_time_s": float(summary["wall_time_s"]), "n_dof": summary.get("n_dof"),
                              "peak_memory_mb": summary.get("peak_memory_mb")}
                except (OSError, ValueError, KeyError, TypeError):
                    continue  # no summary (a refused or failed run) or a damaged entry: no record
                self._earlier[_without_version(key)] = record
        return self._earlier

    def store(self, job: Job, outcome: Outcome) -> Run:
        """Write ``outcome`` atomically (a crash leaves no half run); a failure or a missing
        program is not kept, so the next build tries again."""
        if outcome.status in (FAILED, NOT_INSTALLED):
            return Run(job, outcome.status, outcome.message, None)
        path = self.path(job)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=path.parent, prefix=".partial-"))
        for name, data in (outcome.files or {}).items():
            (tmp / name).write_bytes(data)
        record = {"key": key_of(job), "overrides": dict(job.overrides), "status": outcome.status,
                  "message": outcome.message,
                  "files": {name: _sha256(data) for name, data in sorted((outcome.files or {}).items())},
                  "made": provenance.made()}
        (tmp / "job.json").write_text(json.dumps(record, indent=2, default=str))
        if path.exists():
            shutil.rmtree(path)
        os.replace(tmp, path)
        return _read(job, outcome.status, outcome.message, path)


def made_of(run: Run) -> dict:
    """What ``run``'s entry records of its making (:func:`smfem.studies.provenance.made`; empty
    for a run not stored, or stored before it was recorded)."""
    try:
        return json.loads((run.path / "job.json").read_text()).get("made") or {}
    except (OSError, ValueError, TypeError, AttributeError):
        return {}


def _checked(path: Path) -> tuple[dict | None, str]:
    """The entry's record at ``path`` and what is wrong with the entry ('' if nothing): its
    record, a file, a checksum."""
    try:
        record = json.loads((path / "job.json").read_text())
        files = record["files"]
        record["status"], record["message"]
    except (OSError, ValueError, KeyError, TypeError):
        return None, "job.json is not a record this version writes"
    for name, digest in files.items():
        file = path / name
        if not file.is_file():
            return record, f"{name} is missing"
        if _sha256(file.read_bytes()) != digest:
            return record, f"{name} differs from its checksum"
    return record, ""


def _read(job: Job, status: str, message: str, path: Path) -> Run:
    if (path / "history.csv").exists():
        return Run(job, status, message, path, *read_run(path, fields=False))
    summary = json.loads((path / "summary.json").read_text()) if (path / "summary.json").exists() else None
    return Run(job, status, message, path, None, summary)
