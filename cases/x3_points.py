"""How many stress points along x3 SMFEM's plastic runs take, per scene and harmonic count.

The plastic strains live at points along x3 (:mod:`smfem.sampling`, the rule
:func:`smfem.inhomogeneity.x3_rule`). The fewest
that integrate the kept modes' products exactly leave plastic zones coarse along x3 where few
harmonics are kept; more points cost CPU on every iteration. So the count is a multiple of that
exact count (a power of 2), measured per scene and harmonic count by doubling it until the
plastic-zone area (peps >= 0.1 %, at each of the scene's zone times) moves by at most
:data:`AREA_TOLERANCE` of the zone's largest area when the count doubles once more.

The table, ``x3_points.csv`` beside this module, is made by ``python benchmarks/x3_points.py
--write`` and never edited by hand. A harmonic count not in it takes the factor of the nearest
one measured (by ratio; the larger factor between two); a scene not in it, the exact count.
"""

from __future__ import annotations

import csv
import functools
import math
from pathlib import Path


#: the table (scene, harmonics, exact_points, points, factor, area_change_pct)
TABLE = Path(__file__).with_name("x3_points.csv")
#: the largest change of the plastic-zone area (relative to its largest) one more doubling may make
AREA_TOLERANCE = 0.01


@functools.cache
def _factors() -> dict[str, dict[int, float]]:
    """scene -> harmonics -> factor (read with ``csv``: pandas' first read_csv costs a plastic
    run's CPU 10 ms, a tenth of the thick cylinder's)."""
    if not TABLE.exists():
        return {}
    out: dict[str, dict[int, float]] = {}
    with TABLE.open(newline="") as f:
        for row in csv.DictReader(f):
            out.setdefault(row["scene"], {})[int(row["harmonics"])] = float(row["factor"])
    return out


def oversampling(scene: str, harmonics: int) -> tuple[float, str]:
    """The multiple of the exact point count for ``scene`` at ``harmonics``, and where it came
    from (for the run's record)."""
    measured = _factors().get(scene)
    if not measured:
        return 1.0, "the exact count (no measured count for this scene: benchmarks/x3_points.py --write)"
    distance = {h: abs(math.log(max(harmonics, 1) / h)) for h in measured}
    nearest = min(distance.values())
    h = max((h for h, d in distance.items() if math.isclose(d, nearest)), key=measured.get)
    return measured[h], f"measured for {scene} at {h} harmonics ({TABLE.name})"
