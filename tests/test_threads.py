"""The numerics run on one BLAS/OpenMP thread in every entry point (smfem/runs/threads.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

PROBE = """
import json, sys
from threadpoolctl import threadpool_info
import numpy  # loads the BLAS before the entry point runs, as an importing program would
{entry}
print(json.dumps([p["num_threads"] for p in threadpool_info()]))
"""


@pytest.mark.parametrize("entry", [
    "from smfem.cli import main; main(['cases'])",
    "import smfem; smfem.run('dome', t_end=1e-5, estimate=False, fields=False)",
    "from smfem.studies.jobs import Job, execute; execute(Job.make('dome', 'smfem', {'t_end': 1e-5}))",
])
def test_entry_points_pin_one_thread(entry):
    """In a fresh process (the pools are per process), with no thread variable set."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "SMFEM_THREADS")}
    out = subprocess.run([sys.executable, "-c", PROBE.format(entry=entry)], capture_output=True, text=True,
                         env=env, check=True).stdout
    counts = json.loads(out.strip().splitlines()[-1])
    assert counts and all(n == 1 for n in counts), counts


def test_the_count_can_be_set_for_a_measurement(monkeypatch):
    from threadpoolctl import threadpool_info

    from smfem.runs import threads

    monkeypatch.setenv(threads.VARIABLE, "2")
    assert threads.pin() == 2
    assert all(p["num_threads"] <= 2 for p in threadpool_info())
    monkeypatch.setenv(threads.VARIABLE, "1")
    threads.pin()
