"""One run of a study: what to run (:class:`Job`) and running it (:func:`execute`).

:func:`execute` is what a worker process or a dask worker calls. It returns the files that
``smfem run`` would write, as bytes, so the client stores them: workers need not share a disk.
"""

from __future__ import annotations

import functools
import tempfile
import time
import traceback
from dataclasses import dataclass
from pathlib import Path

from cases import UnsupportedCase, get_case
from cases.params import ToolMissing
from smfem.runs import memory, threads
from smfem.runs.files import write_run
from smfem.runs.registry import FIELDS, Solver, lookup, solve

OK, NOT_CONVERGED, NOT_AVAILABLE, FAILED = "ok", "not converged", "not available", "failed"
#: an optional solver whose program is not on this machine (CalculiX): not kept in the cache,
#: left out of the tables, named in the case's section
NOT_INSTALLED = "not installed"


@dataclass(frozen=True)
class Job:
    """A case with overrides, run by one solver (a name of :mod:`smfem.runs.registry`'s table).

    ``overrides`` is a sorted tuple of ``(key, value)`` so that a job can be hashed, with the
    parameters the solver fixes (its ``dim``, SMFEM's quadratic ``element``); ``fields`` asks a solver that writes fields (SMFEM's, in a study)
    for ``fields.vtu`` and its time series ``fields.pvd`` (and plastic zones, which plastic runs
    always draw); ``options`` (sorted ``(key, value)`` too) are the solver's
    own options (:func:`smfem.runs.registry.solve`), part of the run's identity.
    """

    case: str
    solver: str
    overrides: tuple
    fields: bool = False
    options: tuple = ()

    @classmethod
    def make(cls, case: str, solver: str, overrides: dict, fields: bool = False, options: dict | None = None) -> Job:
        entry = lookup(solver)
        # in the parameters, so the run's record says how it ran
        overrides = dict(overrides, **entry.fixed)
        return cls(case, solver, tuple(sorted(overrides.items())), fields and FIELDS in entry.supports,
                   tuple(sorted((options or {}).items())))

    def build(self):
        """The case with the resolved parameters (raises ParameterError on a bad override),
        resolved once per job: the cache's key, the run's label and the worker all ask."""
        return self.resolved

    @functools.cached_property
    def resolved(self):
        return get_case(self.case, dict(self.overrides))

    @functools.cached_property
    def defaults(self) -> dict:
        """The scene's own parameters, without the job's overrides (read once per job: a scene
        file with a gmsh section takes tens of ms to read)."""
        return get_case(self.case).params

    def describe(self) -> str:
        sets = " ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in self.overrides + self.options)
        return f"{self.scene} {self.solver} {sets}".strip()

    @property
    def scene(self) -> str:
        """The scene's name: a built-in one's, or a scene file's own (``name = ...``), not its path."""
        return self.case if self.resolved.source is None else self.resolved.name


@dataclass
class Outcome:
    """What came back from a worker: status, a message, and the run's files by name."""

    status: str
    message: str = ""
    files: dict | None = None


#: frames of the time series a fields run writes (fields.pvd): the field at t = 0 and about as
#: many more, evenly over the window
SERIES_FRAMES = 5


def series_every(case) -> int:
    """Steps between the frames of a fields run's time series."""
    return max(1, case.n_steps // SERIES_FRAMES)


def solve_job(job: Job, solver: Solver):
    """The solve of ``job`` as a study runs it (its fields, frames and options): the run a timing
    pass repeats (:mod:`smfem.studies.timing`) measures what the study's run measured."""
    case = job.build()
    return solve(solver, case, fields=job.fields, every=series_every(case) if job.fields else 0,
                 options=dict(job.options) or None)


def execute(job: Job, solver: Solver | None = None) -> Outcome:
    """Run ``job`` as ``smfem run`` would and return its files; ``solver``: the entry of
    ``job.solver``, sent along to a worker process, whose table has only the built-in ones.

    A solver that cannot represent the case (:class:`cases.UnsupportedCase`) gives
    ``not available``; any other exception gives ``failed`` with the traceback's last line, so
    that one broken run does not lose a long study.
    """
    threads.pin()  # a dask worker too: a run's CPU means one core's work wherever it runs
    solver = solver or lookup(job.solver)
    case = job.build()
    memory.reset_peak()
    wall0 = time.perf_counter()
    try:
        result = solve_job(job, solver)
    except ToolMissing as exc:
        return Outcome(NOT_INSTALLED, str(exc))
    except UnsupportedCase as exc:
        return Outcome(NOT_AVAILABLE, str(exc))
    except Exception as exc:  # noqa: BLE001 - reported per run, see the docstring
        where = traceback.extract_tb(exc.__traceback__)[-1]
        return Outcome(FAILED, f"{type(exc).__name__}: {exc} ({Path(where.filename).name}:{where.lineno})")
    wall = time.perf_counter() - wall0
    with tempfile.TemporaryDirectory(prefix="smfem-job-") as tmp:
        out = Path(tmp)
        # the zones' data only: the report draws the figure it shows (SMFEM beside the reference)
        write_run(out, case, solver.family, result, wall, zone_figure=False, extra={"peak_memory_mb": memory.peak_mb()})
        files = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    return Outcome(OK if result.converged else NOT_CONVERGED, result.message, files)
