"""Where the runs of a study execute: local worker processes, or a dask.distributed cluster.

Both yield ``(job, outcome)`` as runs finish, in whatever order they finish.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, as_completed

from runs import threads

from .jobs import Job, execute

#: one BLAS/OpenMP thread per worker from its start (``execute`` pins it again, for dask's
#: workers): two workers on two cores must not oversubscribe
THREAD_VARIABLES = threads.LIBRARY_VARIABLES


@contextlib.contextmanager
def _single_threaded_children():
    """Set the thread variables (unless the user set them) for processes started meanwhile."""
    saved = {k: os.environ.get(k) for k in THREAD_VARIABLES}
    for k in THREAD_VARIABLES:
        os.environ.setdefault(k, "1")
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)


def local(jobs: list[Job], workers: int):
    """Run ``jobs`` on ``workers`` fresh processes (spawned: numpy reads the thread variables
    when it loads, and a forked child would inherit the parent's thread pools)."""
    with _single_threaded_children(), ProcessPoolExecutor(
        max_workers=workers, mp_context=multiprocessing.get_context("spawn")
    ) as pool:
        futures = {pool.submit(execute, job): job for job in jobs}
        for future in as_completed(futures):
            yield futures[future], future.result()


class SchedulerUnreachable(OSError):
    """No dask scheduler answers at the address given."""


def dask(jobs: list[Job], address: str, timeout: str = "20s"):
    """Run ``jobs`` on the dask.distributed scheduler at ``address`` (its workers need this
    package installed; they send back the run's files, so they need not share a disk)."""
    from distributed import Client, as_completed as dask_completed

    try:
        client = Client(address, timeout=timeout)
    except OSError as exc:
        raise SchedulerUnreachable(f"--scheduler {address}: no dask scheduler answers there ({exc})") from None
    with client:
        futures = {client.submit(execute, job, pure=False): job for job in jobs}
        for future in dask_completed(list(futures)):
            yield futures[future], future.result()


def run_jobs(jobs: list[Job], scheduler: str | None = None, workers: int = 2):
    """Dispatch to :func:`dask` when a scheduler address is given, else :func:`local`."""
    if not jobs:
        return iter(())
    return dask(jobs, scheduler) if scheduler else local(jobs, workers)
