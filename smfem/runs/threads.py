"""One BLAS/OpenMP thread for the numerics, in every entry point.

The solvers' dense work is small (element blocks, Woodbury's low-rank factors, sparse
triangular solves): at these sizes a second thread only waits and spins. Measured on this
2-core machine, ``smfem run notched_strip --no-fields``: two threads cost 5.1 s CPU idle (3.9 s
wall) and 8.5 s CPU with the other core busy (7.8 s wall); one thread 3.1-3.2 s CPU idle (4.5 s
wall) and 3.0-3.2 s busy (4.4-4.9 s wall).
One thread also makes CPU times comparable between a plain run and the report's workers (which
are pinned the same way) and keeps two workers on two cores from oversubscribing.

``SMFEM_THREADS`` sets another count (for a measurement on a larger machine); it overrides the
libraries' own variables.
"""

from __future__ import annotations

import os

from threadpoolctl import threadpool_limits

#: the environment variable that sets another count
VARIABLE = "SMFEM_THREADS"

#: read by the BLAS and OpenMP libraries when they load (scipy's own OpenBLAS loads later than
#: numpy's, with the first scipy.linalg call)
LIBRARY_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")

_limits = None  # kept alive: the limits hold while this object exists


def pin() -> int:
    """Limit the BLAS and OpenMP pools of this process, those loaded (threadpoolctl) and those
    still to load (their variables); returns the count set."""
    global _limits
    count = max(int(os.environ.get(VARIABLE, "1") or 1), 1)
    for name in LIBRARY_VARIABLES:
        os.environ[name] = str(count)
    _limits = threadpool_limits(limits=count)
    return count
