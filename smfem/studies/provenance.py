"""Which source a run was made from: the git commit of the checkout that made it.

The run cache keys a run by a hash of the sources its results depend on, so a report may take a
run made by an earlier commit whose numerics are the same. A published report says how many of
its runs were made from the sources it was made with (``run.json``): one made "from nothing at
the final commit" has every run made by a commit whose :data:`SOURCES` (what decides the runs)
equal that commit's,
whether by one pass of the command or by several into the same new cache (a full report can
outlast a working session; a stopped pass leaves its finished runs stored, and a commit of
README alone between two passes changes no source).
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


def _git(*args) -> str:
    return subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True, check=True,
                          timeout=30).stdout.strip()


@functools.cache
def commit() -> str | None:
    """HEAD's hash, with ``+changes`` when tracked files differ from it (the run then comes from
    no commit), or None outside a git checkout or without git."""
    try:
        head = _git("rev-parse", "HEAD")
        changed = _git("status", "--porcelain", "--untracked-files=no")
    except (OSError, subprocess.SubprocessError):
        return None
    return head + ("+changes" if changed else "")


@functools.cache
def same_sources(made_by: str | None) -> bool:
    """Whether a run recorded as made by commit ``made_by`` came from the :data:`SOURCES` that this
    checkout has now (a commit with changes, or none, is never known to)."""
    if not made_by or "+" in made_by:
        return False
    try:
        _git("diff", "--quiet", made_by, "--", *SOURCES)
    except (OSError, subprocess.SubprocessError):
        return False  # they differ (exit 1), or the commit is unknown here
    return True


def made() -> dict:
    """What a stored run records of its making: the commit and the time."""
    return {"commit": commit(), "at": time.strftime("%Y-%m-%d %H:%M:%S %Z")}
