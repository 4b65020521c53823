"""What every subcommand shares: the one-line usage error, exit statuses, output checks."""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

EXIT_USAGE, EXIT_NOT_CONVERGED = 2, 3


class UsageError(Exception):
    """A user mistake with a one-line explanation."""


class Parser(argparse.ArgumentParser):
    """An argument parser whose mistakes are :class:`UsageError` (one line, exit 2), not a
    usage dump."""

    def error(self, message):
        raise UsageError(message)


def check_writable(out: Path, flag: str = "--out") -> None:
    """Fail early, before any work and without leaving anything, if ``out`` cannot be written.

    Tries to make a scratch directory in the nearest existing ancestor: permission bits alone
    do not tell (root, read-only or virtual file systems).
    """
    probe = out.absolute()
    while not probe.exists():
        probe = probe.parent
    if out.exists() and not out.is_dir():
        raise UsageError(f"{flag} {out}: exists and is not a directory")
    try:
        os.rmdir(tempfile.mkdtemp(dir=probe, prefix=".smfem-write-test-"))
    except OSError as exc:
        raise UsageError(f"{flag} {out}: cannot write there ({exc.strerror})") from None


def add_sets(p, help_text: str | None = None, dest: str = "sets", flag: str = "--set") -> None:
    p.add_argument(flag, dest=dest, action="append", default=[], metavar="KEY=VALUE", help=help_text)


def add_study_options(p, default_out: str | None) -> None:
    """``--quick | --full``, ``--out``, ``--cache``, ``--scheduler``, ``--workers``, ``--quiet``."""
    size = p.add_mutually_exclusive_group()
    size.add_argument("--quick", action="store_true", help="the quick study (the default; minutes on two cores)")
    size.add_argument("--full", action="store_true", help="the larger study")
    p.add_argument("--out", default=default_out, help=f"output directory (default {default_out or 'out/CASE-truth'})")
    p.add_argument("--cache", default=None, help="run cache directory (default OUT/runs)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="dask.distributed scheduler address (default: local processes)")
    p.add_argument("--workers", type=int, default=2, help="local worker processes (default 2)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


#: the most local worker processes (each holds a solver's matrices)
MAX_WORKERS = 256


def check_workers(args) -> None:
    if not 1 <= args.workers <= MAX_WORKERS:
        raise UsageError(f"--workers={args.workers} is out of range: --workers must be an integer in [1, {MAX_WORKERS}]")
