"""Memory-aware scheduling (smfem/studies/peak_memory.py, smfem/studies/executors.py::local):
runs whose predicted peaks together pass the limit never run at the same time, and a run's peak
is predicted from the run cache's record."""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor

import pytest

from smfem.studies.executors import local
from smfem.studies.jobs import Job
from smfem.studies.peak_memory import MB, MemoryLimit, PeakMemory

GB = 1e9


def _run(peaks: dict, limit: float, workers: int = 2) -> dict:
    """Every job of ``peaks`` through :func:`local` on a thread pool, each holding its worker
    50 ms; returns each job's (start, end) on the monotonic clock."""
    spans = {}

    def fake(job):
        start = time.monotonic()
        time.sleep(0.05)
        spans[job] = (start, time.monotonic())
        return "ok"

    with ThreadPoolExecutor(workers) as pool:
        done = [job for job, _ in local(list(peaks), workers, MemoryLimit(peaks.__getitem__, limit),
                                        start=lambda job: pool.submit(fake, job))]
    assert sorted(done) == sorted(peaks)
    return spans


def _overlap(spans: dict, a, b) -> bool:
    return spans[a][0] < spans[b][1] and spans[b][0] < spans[a][1]


def test_two_runs_whose_predicted_peaks_pass_the_limit_never_run_together():
    peaks = {"big": 8 * GB, "bigger": 9 * GB, "small": 1 * GB, "small2": 1 * GB, "small3": 1 * GB}
    spans = _run(peaks, limit=10 * GB)
    assert not _overlap(spans, "big", "bigger")
    # the small ones run beside a big one meanwhile: two workers stay busy where memory allows
    assert _overlap(spans, "big", "small")


def test_a_run_predicted_over_the_limit_alone_runs_alone():
    spans = _run({"huge": 30 * GB, "small": 1 * GB, "small2": 1 * GB}, limit=10 * GB)
    assert not _overlap(spans, "huge", "small") and not _overlap(spans, "huge", "small2")


def test_without_a_limit_two_workers_run_two_at_a_time():
    spans = _run({"a": 8 * GB, "b": 9 * GB}, limit=float("inf"))
    assert _overlap(spans, "a", "b")


class _Record:
    """A run cache's record as :class:`PeakMemory` reads it (RunCache.earlier, .previous)."""

    def __init__(self, records: list[dict], previous: dict | None = None):
        self.records, self.known = records, previous or {}

    def earlier(self) -> dict:
        return {str(i): r for i, r in enumerate(self.records)}

    def previous(self, job):
        return self.known.get(job)


def _dome(refine: int) -> dict:
    return {"case": "dome", "solver": "reference-2d", "params": {"refine": refine, "dt": 1e-6, "t_end": 1e-4}}


def test_a_peak_is_the_recorded_one_else_scaled_from_its_relatives_unknowns():
    recorded = [_dome(1) | {"n_dof": 1000, "peak_memory_mb": 150.0},
                _dome(2) | {"n_dof": 4000, "peak_memory_mb": 190.0}]
    again = Job.make("dome", "reference-2d", {"refine": 2})
    finer = Job.make("dome", "reference-2d", {"refine": 4})
    peaks = PeakMemory(_Record(recorded, {again: {"peak_memory_mb": 191.0}}))
    assert peaks(again) == pytest.approx(191.0 * MB)
    # refine 4: 4 x the unknowns of refine 2 at its 10 kB per unknown above the process's 150 MB
    assert peaks(finer) == pytest.approx(150 * MB + 16000 * 40 * MB / 4000)
    assert peaks(Job.make("thick_cylinder", "reference-2d", {})) == 0.0  # no relative on record


def _die_or_sleep(job: str) -> str:
    """A worker's run: ``'bad'`` kills its own process (as the system's out-of-memory killer
    would), the others take 0.3 s."""
    import os
    import signal

    if job == "bad":
        os.kill(os.getpid(), signal.SIGKILL)
    time.sleep(0.3)
    return "ok"


def test_a_run_whose_worker_is_killed_is_failed_and_the_study_goes_on():
    """A worker killed mid-run breaks the pool and every run on it (a raw BrokenProcessPool
    before): the runs go again, each alone, on a new pool; the one that dies again alone is
    failed with one line, the others come back as they are, and the queue goes on."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    from smfem.studies.executors import KILLED
    from smfem.studies.jobs import FAILED, Outcome

    pools = []

    def start(job):
        if not pools or pools[-1]._broken:
            pools.append(ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("fork")))
        return pools[-1].submit(_die_or_sleep, job)

    try:
        outcomes = dict(local(["good", "bad", "after", "last"], 2, start=start))
    finally:
        for pool in pools:
            pool.shutdown(wait=True)
    assert outcomes == {"good": "ok", "bad": Outcome(FAILED, KILLED), "after": "ok", "last": "ok"}
    assert len(pools) >= 3  # the first broke, and so did the one where "bad" ran again alone
