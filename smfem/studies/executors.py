"""Where the runs of a study execute: local worker processes, or a dask.distributed cluster.

Both take the jobs as a queue (a list) that the caller may extend while it iterates (the next
level of a series carried to a target, :mod:`smfem.studies.study`), and yield ``(job, outcome)`` as
runs finish, in whatever order they finish; a job appended is submitted once the caller asks
for the next outcome.
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

from smfem.runs.registry import lookup

from .jobs import FAILED, Job, Outcome, execute
from .peak_memory import MemoryLimit


class _Feed:
    """The jobs of ``queue`` not submitted yet, taken once each, in order."""

    def __init__(self, queue: list[Job]):
        self.queue, self.taken = queue, 0

    def new(self) -> list[Job]:
        jobs, self.taken = self.queue[self.taken:], len(self.queue)
        return jobs


#: environment variables that change under a running session and that no worker reads: pytest
#: names the current test in one, which would otherwise spawn every test its own pool
_NOT_READ = frozenset({"PYTEST_CURRENT_TEST"})

#: the local worker processes, kept between studies of one session (each spawned process
#: imports numpy, scipy, the solvers: one to three CPU seconds before its first job)
_pool: tuple[tuple, ProcessPoolExecutor] | None = None


def _workers(count: int) -> ProcessPoolExecutor:
    """The session's pool of ``count`` spawned processes; a pool of another size, or one spawned
    under other environment variables (``SMFEM_THREADS``, ``SMFEM_CCX``: a process reads them
    from the environment it was started with) is shut down and replaced."""
    global _pool
    key = (count, tuple(sorted(item for item in os.environ.items() if item[0] not in _NOT_READ)))
    if _pool is not None and _pool[0] != key:
        _discard()
    if _pool is None:
        _pool = (key, ProcessPoolExecutor(max_workers=count, mp_context=multiprocessing.get_context("spawn")))
    return _pool[1]


def _discard() -> None:
    global _pool
    _pool[1].shutdown(wait=True, cancel_futures=True)
    _pool = None


def _submit(count: int, fn, *args):
    """``fn(*args)`` on the session's pool of ``count``; a pool broken by a process that died
    (in an earlier study, say) is replaced first."""
    try:
        return _workers(count).submit(fn, *args)
    except BrokenProcessPool:
        _discard()
        return _workers(count).submit(fn, *args)


def in_worker(fn, *args, workers: int = 2):
    """``fn(*args)`` in one of the session's ``workers`` local processes, as a Future: work that
    overlaps the caller's (the report's tables that are not runs, while it draws figures)."""
    return _submit(workers, fn, *args)


def local(queue: list[Job], workers: int, limit: MemoryLimit | None = None, start=None):
    """Run the jobs of ``queue`` on ``workers`` processes, spawned (a forked child would
    inherit the parent's thread pools) once in a session and kept for the next study; each
    pins its BLAS threads in :func:`~smfem.studies.jobs.execute`. Each job goes with its
    solver's entry: a solver registered here is not in a spawned process's table. At most
    ``workers`` jobs are started at once, in queue order; with a ``limit``
    (:class:`~smfem.studies.peak_memory.MemoryLimit`) a job starts only while its predicted peak
    and the running jobs' stay within it, a later one that fits taking its turn meanwhile.
    ``start(job) -> Future``: how a job starts (default: on the session's pool). Left early
    (the caller stops iterating, or an error), the jobs not started are dropped and the
    running ones finish before it returns, as they did when each study had its own pool.

    A worker that dies mid-run (killed by the system's out-of-memory killer, say) breaks the
    pool and every run on it: those runs go again, each alone, on a new pool, and one that dies
    alone is recorded :data:`KILLED` (``failed``); the study goes on.
    """
    start = start or (lambda job: _submit(workers, execute, job, lookup(job.solver)))
    feed, waiting, pending = _Feed(queue), [], {}
    suspects, alone = [], []  # runs on a pool that broke; those running alone after it

    def submit():
        waiting.extend(feed.new())
        while len(pending) < workers and (waiting or suspects):
            if any(job in alone for job in pending.values()):
                return
            if suspects:  # after the runs still going, alone, so that a second death names its run
                if not pending:
                    job = suspects.pop(0)
                    alone.append(job)
                    pending[start(job)] = job
                return
            job = limit.pick(waiting, list(pending.values())) if limit else waiting[0]
            if job is None:
                return
            waiting.remove(job)
            pending[start(job)] = job

    try:
        submit()
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                job = pending.pop(future)
                try:
                    outcome = future.result()
                except BrokenProcessPool:
                    if job not in alone:
                        suspects.append(job)
                        continue
                    outcome = Outcome(FAILED, KILLED)
                if job in alone:
                    alone.remove(job)
                yield job, outcome
            submit()
    finally:
        for future in pending:
            future.cancel()
        wait(pending)


#: a run whose worker died under it twice, the second time alone
KILLED = ("its worker process died under it, also when run alone: killed by the system, most likely for "
          "memory (see dmesg)")


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


def run_jobs(queue: list[Job], scheduler: str | None = None, workers: int = 2, limit: MemoryLimit | None = None):
    """Dispatch to :func:`dask` when a scheduler address is given (its own scheduler places the
    runs: ``limit`` does not apply), else :func:`local`."""
    if not queue:
        return iter(())
    return dask(queue, scheduler) if scheduler else local(queue, workers, limit)
