"""Which source a run was made from: the git commit of the checkout that made it.

The run cache keys a run by a hash of the sources its results depend on, so a report may take a
run made by an earlier commit whose numerics are the same. A published report says how many of
its runs were made from the sources it was made with (``run.json``): one made "from nothing at
the final commit" has every run made by a commit whose sources of that run
(:func:`sources_of`: its solver's package, the scenes, the runner and the study framework) equal
that commit's, whether by one pass of the command or by several into the same new cache (a full
report can outlast a working session; a stopped pass leaves its finished runs stored, and a
commit of README alone between two passes changes no source).
"""

from __future__ import annotations

import functools
import subprocess
import time
from pathlib import Path

#: the checkout holding the package, when it is one (an installed wheel is not)
ROOT = Path(__file__).resolve().parents[2]
#: what decides a report's runs: the solvers' numerics, the scenes, the study plan and the runner
#: (its pages, ``reports/``, are written by the last pass from the last sources whatever made the
#: runs; the tests and docs decide nothing)
SOURCES = ("smfem", "reference_fem", "cases", "pyproject.toml")
#: what decides every run besides its solver's packages: the scenes, the runner that calls the
#: solver and measures it, the study framework that plans and executes it, the dependencies
COMMON = ("cases", "smfem/runs", "smfem/studies", "pyproject.toml")
#: what no run passes through: the plan decides which runs a report asks for (the ladders, where
#: each stops), this module where the runs came from and the timing pass how often the decisive
#: ones are timed again (its times are the last pass's, its log resumed only by the same rule and
#: module: ``reports.timing``), the command line what a user asked for (a study's runs go from the
#: plan to ``jobs.execute``, never through it; the run cache's key leaves it out too,
#: ``cache.FRAMEWORK``), never what a run gives, so a run made before a change to them is the run
#: the changed framework would make
NOT_IN_A_RUN = ("smfem/studies/plan.py", "smfem/studies/provenance.py", "smfem/studies/timing.py", "smfem/cli")


def sources_of(packages: tuple[str, ...]) -> tuple[str, ...]:
    """The :data:`SOURCES` that decide a run of a solver whose numerics are ``packages`` (dotted,
    :attr:`smfem.runs.registry.Solver.packages`): a change to SMFEM's numerics leaves the
    reference's runs made from these sources, and the other way round (the two share no numerics)."""
    return tuple(sorted({p.replace(".", "/") for p in packages} | set(COMMON)))


def _git(*args) -> str:
    return subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True, check=True,
                          timeout=30).stdout.strip()


@functools.cache
def commit(paths: tuple[str, ...] = ()) -> str | None:
    """HEAD's hash, with ``+changes`` when tracked files under ``paths`` (all: empty) differ from
    it (what they made then comes from no commit), or None outside a git checkout or without git."""
    try:
        head = _git("rev-parse", "HEAD")
        changed = _git("status", "--porcelain", "--untracked-files=no", "--", *paths)
    except (OSError, subprocess.SubprocessError):
        return None
    return head + ("+changes" if changed else "")


@functools.cache
def same_sources(made_by: str | None, paths: tuple[str, ...] = SOURCES) -> bool:
    """Whether a run recorded as made by commit ``made_by`` came from the ``paths`` (default: all
    :data:`SOURCES`; one solver's: :func:`sources_of`) that this checkout has now (a commit with
    changes, or none, is never known to); :data:`NOT_IN_A_RUN` aside."""
    if not made_by or "+" in made_by:
        return False
    try:
        _git("diff", "--quiet", made_by, "--", *paths, *(f":(exclude){p}" for p in NOT_IN_A_RUN))
    except (OSError, subprocess.SubprocessError):
        return False  # they differ (exit 1), or the commit is unknown here
    return True


def made() -> dict:
    """What a stored run records of its making: the commit and the time. Only :data:`SOURCES`
    decide a run, so an edit elsewhere (README, the docs, the tests) while a report runs leaves
    its runs made from the commit."""
    return {"commit": commit(SOURCES), "at": time.strftime("%Y-%m-%d %H:%M:%S %Z")}
