"""Where the runs of a study execute: local worker processes, or a dask.distributed cluster.

Both yield ``(job, outcome)`` as runs finish, in whatever order they finish.
"""

from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor, as_completed

from runs.registry import lookup

from .jobs import Job, execute


def local(jobs: list[Job], workers: int):
    """Run ``jobs`` on ``workers`` fresh processes (spawned: a forked child would inherit the
    parent's thread pools); each pins its BLAS threads in :func:`~studies.jobs.execute`. Each
    job goes with its solver's entry: a solver registered here is not in a fresh process's table."""
    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = {pool.submit(execute, job, lookup(job.solver)): job for job in jobs}
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
        futures = {client.submit(execute, job, lookup(job.solver), pure=False): job for job in jobs}
        for future in dask_completed(list(futures)):
            yield futures[future], future.result()


def run_jobs(jobs: list[Job], scheduler: str | None = None, workers: int = 2):
    """Dispatch to :func:`dask` when a scheduler address is given, else :func:`local`."""
    if not jobs:
        return iter(())
    return dask(jobs, scheduler) if scheduler else local(jobs, workers)
