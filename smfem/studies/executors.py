"""Where the runs of a study execute: local worker processes, or a dask.distributed cluster.

Both take the jobs as a queue (a list) that the caller may extend while it iterates (the next
level of a series carried to a target, :mod:`smfem.studies.study`), and yield ``(job, outcome)`` as
runs finish, in whatever order they finish; a job appended is submitted once the caller asks
for the next outcome.
"""

from __future__ import annotations

import multiprocessing
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

from smfem.runs.registry import lookup

from .jobs import Job, execute


class _Feed:
    """The jobs of ``queue`` not submitted yet, taken once each, in order."""

    def __init__(self, queue: list[Job]):
        self.queue, self.taken = queue, 0

    def new(self) -> list[Job]:
        jobs, self.taken = self.queue[self.taken:], len(self.queue)
        return jobs


def local(queue: list[Job], workers: int):
    """Run the jobs of ``queue`` on ``workers`` fresh processes (spawned: a forked child would
    inherit the parent's thread pools); each pins its BLAS threads in
    :func:`~smfem.studies.jobs.execute`. Each job goes with its solver's entry: a solver registered
    here is not in a fresh process's table."""
    feed = _Feed(queue)
    with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        pending = {}

        def submit():
            pending.update({pool.submit(execute, job, lookup(job.solver)): job for job in feed.new()})

        submit()
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                yield pending.pop(future), future.result()
                submit()


class SchedulerUnreachable(OSError):
    """No dask scheduler answers at the address given."""


def dask(queue: list[Job], address: str, timeout: str = "20s"):
    """Run the jobs of ``queue`` on the dask.distributed scheduler at ``address`` (its workers
    need this package installed; they send back the run's files, so they need not share a disk)."""
    from distributed import Client, as_completed as dask_completed

    try:
        client = Client(address, timeout=timeout)
    except OSError as exc:
        raise SchedulerUnreachable(f"--scheduler {address}: no dask scheduler answers there ({exc})") from None
    feed = _Feed(queue)
    with client:
        jobs = {}

        def submit():
            new = {client.submit(execute, job, lookup(job.solver), pure=False): job for job in feed.new()}
            jobs.update(new)
            return list(new)

        running = dask_completed(submit())
        for future in running:
            yield jobs.pop(future), future.result()
            for more in submit():
                running.add(more)


def run_jobs(queue: list[Job], scheduler: str | None = None, workers: int = 2):
    """Dispatch to :func:`dask` when a scheduler address is given, else :func:`local`."""
    if not queue:
        return iter(())
    return dask(queue, scheduler) if scheduler else local(queue, workers)
