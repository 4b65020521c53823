"""A run's peak memory: the resident set's high-water mark of the process that ran it.

On Linux the mark is reset before a run (``/proc/self/clear_refs``), so that a worker process
that runs one job after another states each job's own peak; elsewhere it is the process's peak
so far, an upper bound. An external program's (CalculiX's) is the largest child process's peak
so far in this process, an upper bound too.
"""

from __future__ import annotations

import resource
import sys
from pathlib import Path

_STATUS, _CLEAR = Path("/proc/self/status"), Path("/proc/self/clear_refs")
#: ru_maxrss's unit: kilobytes on Linux, bytes on macOS
_RUSAGE_UNIT = 1 if sys.platform == "darwin" else 1024


def reset_peak() -> bool:
    """Start the high-water mark again from the current resident set; False where the system
    cannot (the mark is then the process's peak so far)."""
    try:
        _CLEAR.write_text("5")
        return True
    except OSError:
        return False


def _high_water_mark() -> int | None:
    """This process's resident high-water mark, bytes, from /proc (the one :func:`reset_peak`
    resets; getrusage's never falls); None where /proc does not say."""
    try:
        line = next(x for x in _STATUS.read_text().splitlines() if x.startswith("VmHWM:"))
        return int(line.split()[1]) * 1024
    except (OSError, StopIteration, ValueError):
        return None


def peak_mb() -> float:
    """The peak resident memory, MB (10^6 bytes), of this process since :func:`reset_peak` and
    of its largest child process so far."""
    own = _high_water_mark() or resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * _RUSAGE_UNIT
    children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * _RUSAGE_UNIT
    return max(own, children) / 1e6
