"""Reading CalculiX's ASCII result file (``.frd``): nodal result blocks per increment.

A block is a ``100CL`` header (the step time in columns 13-24), a ``-4`` line naming the
result (``DISP``, ``VELO``, ``STRESS``, ``PE`` ..., ``FORC``), ``-5`` component lines and one
``-1`` line per node: the node number in columns 4-13, then the values in 12-column fields.
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

import numpy as np


def read_frd(path: Path, names: set[str]) -> dict[str, list[tuple[float, np.ndarray, np.ndarray]]]:
    """Per result name in ``names``, one ``(time, nodes, values)`` per increment: node numbers
    ``(n,)`` and values ``(n, components)``."""
    blocks = defaultdict(list)
    lines = Path(path).read_bytes().splitlines()
    k, n = 0, len(lines)
    while k < n:
        line = lines[k]
        if line.startswith(b"  100C"):
            t = float(line[12:24])
            name = lines[k + 1][5:11].strip().decode()
            k += 2
            while k < n and lines[k].startswith(b" -5"):
                k += 1
            start = k
            while k < n and not lines[k].startswith(b" -3"):
                k += 1
            if name in names and k < n:  # a block cut short by a failed run is left out
                blocks[name].append((t, *_values(lines[start:k])))
        k += 1
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
