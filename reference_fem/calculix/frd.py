"""Reading CalculiX's ASCII result file (``.frd``): nodal result blocks per increment.

A block is a ``100CL`` header (the step time in columns 13-24), a ``-4`` line naming the
result (``DISP``, ``VELO``, ``STRESS``, ``PE`` ..., ``FORC``), ``-5`` component lines and one
``-1`` line per node: the node number in columns 4-13, then the values in 12-column fields.
"""

from __future__ import annotations

import mmap
import os
from collections import defaultdict
from pathlib import Path
from typing import Callable

import numpy as np


def read_frd(path: Path, names: set[str], reduce: Callable | None = None) -> dict[str, list[tuple]]:
    """Per result name in ``names``, one ``(time, *reduce(name, nodes, values))`` per increment:
    node numbers ``(n,)`` and values ``(n, components)``, as they are or as ``reduce`` keeps them.

    The file is mapped, not read: the blocks of other results are stepped over, and each kept
    one is parsed and reduced on its own. An explicit run's .frd can hold gigabytes; as one
    bytes object per line it took over 20 GB (the notched cylinder at refine 4)."""
    blocks = defaultdict(list)
    with open(path, "rb") as f:
        if os.fstat(f.fileno()).st_size == 0:
            return {}
        with mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as mm:
            k = mm.find(b"\n  100C")
            while k >= 0:
                header_end = mm.find(b"\n", k + 1)
                name_end = mm.find(b"\n", header_end + 1)
                end = mm.find(b"\n -3", name_end)
                if header_end < 0 or name_end < 0 or end < 0:
                    break  # a block cut short by a failed run is left out
                name = mm[header_end + 1 : name_end][5:11].strip().decode()
                if name in names:
                    t = float(mm[k + 1 : header_end][12:24])
                    lines = mm[name_end + 1 : end].splitlines()
                    data = [line for line in lines if not line.startswith(b" -5")]
                    nodes, values = _values(data) if data else (np.zeros(0, int), np.zeros((0, 0)))
                    blocks[name].append((t, *(reduce(name, nodes, values) if reduce else (nodes, values))))
                k = mm.find(b"\n  100C", end)
    return dict(blocks)


def read_sta(path: Path) -> list[tuple[float, int]]:
    """``(time, iterations)`` of each converged increment in ccx's ``.sta`` file (a failed
    attempt's iterations counted into the increment that follows it)."""
    out, pending = [], 0
    for line in Path(path).read_text().splitlines()[2:]:
        parts = line.split()
        if len(parts) < 7:
            continue
        its = int(parts[3])
        if parts[2].endswith("U"):
            pending += its
            continue
        out.append((float(parts[4]), its + pending))
        pending = 0
    return out


def _values(data: list[bytes]) -> tuple[np.ndarray, np.ndarray]:
    """Node numbers and values of the ``-1`` lines of one block (fixed columns)."""
    width = max(len(line) for line in data)
    raw = np.frombuffer(b"".join(line.ljust(width) for line in data), dtype=f"S{width}")
    chars = raw.view("S1").reshape(len(data), width)
    nodes = chars[:, 3:13].copy().view("S10").ravel().astype(int)
    m = (width - 13) // 12
    values = chars[:, 13 : 13 + 12 * m].copy().view("S12").reshape(len(data), m).astype(float)
    return nodes, values
