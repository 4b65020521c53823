"""Time a run only while the host is quiet: a probe of its memory speed before each batch of the
timing pass (:mod:`reports.timing`).

On a shared machine a neighbour that takes memory bandwidth slows a memory-bound run (sparse
solves, conjugate gradients) more than a compute-bound one, so the two sides of a speed-up move
apart: two retimes of one quick report disagreed by 32.5 % on the notched cylinder, whose 2D
reference (CG) took 26.7 CPU s at its least over four repeats in one pass, 18.0 in the other,
and 19.9-21.2 s four times in a row on an idle host, while SMFEM's run stayed at 6.7 s. Before
each batch the worker streams a fixed array through memory (:func:`memory_probe`); where that
takes more than :attr:`HostGate.slack` over the least the pass has seen, the pass waits and
probes again, up to :attr:`HostGate.waits` times, then times the batch anyway. Only a batch
expected to take :data:`WORTH_WAITING_S` or more waits: a short run's least repeat among many
finds a quiet moment by itself, and a pass whose budget the cheap runs spent times the dear,
memory-bound runs, the ones that disagreed, on whatever host it finds (a quick report's retime,
2026-11-30, spent its 30 minutes within its first sweep, 24 batches waiting, a 0.4 s CalculiX run
six times among them). The slack sits above the probe's own
scatter on a quiet host (160 probes of one pass: best 9.1 ms, median 10.7, 90th percentile 15.3,
most 21.7): at 10 % most probes waited. Each batch's probe goes into
``tables/timing_repeats.csv``, so what the host did stays on record.
"""

from __future__ import annotations

import math
import time

import numpy as np

from smfem.studies.executors import in_worker
from smfem.studies.timing import in_one_worker

#: floats streamed by the probe: 32 MB a pass, past the caches of this machine's cores
PROBE_FLOATS = 4_000_000
#: how many times a batch waits for a quiet host (:class:`HostGate`) in a full report or a retime
WAITS = 6
#: the most a whole pass waits, s: a host that stays slow (or a best probe that was luck) must not
#: hold a full report's pass for hours; beyond it the probes are still recorded
WAIT_BUDGET_S = 1800.0
#: the least CPU s a batch is expected to take (its study shot times its repeats) for it to wait
WORTH_WAITING_S = 2.0
#: how far over the best probe the host counts as quiet
SLACK = 0.25


def memory_probe(passes: int = 4) -> float:
    """CPU s of ``passes`` in-place additions of two arrays of :data:`PROBE_FLOATS`, the least of
    three: the time a stream through memory takes now (a core stalled on memory still counts
    its CPU time, as the runs' CPU times do)."""
    a, b = np.ones(PROBE_FLOATS), np.ones(PROBE_FLOATS)
    best = math.inf
    for _ in range(3):
        t = time.process_time()
        for _ in range(passes):
            np.add(a, b, out=a)
        best = min(best, time.process_time() - t)
    return best


def in_the_timing_worker(fn, *args):
    """``fn(*args)`` in the worker the pass times its runs in (:func:`in_one_worker`'s)."""
    return in_worker(fn, *args, workers=1).result()


class HostGate:
    """``run(job, repeats)`` (:func:`in_one_worker`) once the host's memory speed is within
    ``slack`` of the best probe so far, waiting ``wait_s`` between probes at most ``waits`` times
    a batch and ``budget_s`` in all, where the batch is expected to take ``worth_s`` or more
    (``expected``: a job's CPU s a repeat, its study shot; a job not in it is expected dear);
    ``probe`` and ``sleep`` stand in for the worker's probe and the clock in tests."""

    def __init__(self, run=in_one_worker, slack: float = SLACK, waits: int = WAITS, wait_s: float = 20.0,
                 budget_s: float = WAIT_BUDGET_S, probe=lambda: in_the_timing_worker(memory_probe),
                 sleep=time.sleep, worth_s: float = WORTH_WAITING_S):
        self.run, self.slack, self.waits, self.wait_s, self.budget_s = run, slack, waits, wait_s, budget_s
        self.probe, self.sleep, self.worth_s = probe, sleep, worth_s
        self.expected: dict = {}
        self.best, self.waited_s = math.inf, 0.0
        #: the probe (CPU s) before the last batch, and how many times it waited
        self.last_probe, self.last_waits = math.nan, 0

    def __call__(self, job, repeats: int) -> list[float]:
        may_wait = self.expected.get(job, math.inf) * repeats >= self.worth_s
        for waited in range(self.waits + 1):
            probe = self.probe()
            self.best = min(self.best, probe)
            if (not may_wait or probe <= self.best * (1 + self.slack) or waited == self.waits
                    or self.waited_s + self.wait_s > self.budget_s):
                break
            self.sleep(self.wait_s)
            self.waited_s += self.wait_s
        self.last_probe, self.last_waits = probe, waited
        return self.run(job, repeats)
