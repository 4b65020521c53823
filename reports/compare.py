"""One case run by SMFEM and by the reference FEM, side by side.

Writes both runs (``smfem/`` and ``reference/``, each as ``smfem run`` would), then
``comparison.csv`` (one row per probe), ``histories.png`` (both histories per probe) and, for
plastic runs, ``plastic_zones.png`` with SMFEM's zones above the reference's at the same times.

Errors: relative max-norm over the window, ``max|a - b| / max|b|``, for displacements,
velocities and stresses; for plastic-strain probes the relative difference of the peaks; for
plastic runs also the area of the plastic zone (peps >= 0.1 %) at each of the paper's times.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pandas as pd

from smfem.runs.errors import probe_error
from smfem.runs.files import write_run
from smfem.runs.figures import plastic_zones, save, subplots
from smfem.runs.registry import REFERENCE, SMFEM, solve
from smfem.runs.zones import plastic_area


def comparison_table(smfem_result, reference_result) -> pd.DataFrame:
    rows = []
    for name, a in smfem_result.history.items():
        b = reference_result.history[name]
        measure, value = probe_error(name, smfem_result.t, a, reference_result.t, b)
        rows.append({"probe": name, "measure": measure, "relative_error": value,
                     "smfem_peak": float(np.abs(a).max()), "reference_peak": float(np.abs(b).max())})
    for a, b in zip(smfem_result.snapshots, reference_result.snapshots):
        sa, sb = plastic_area(a), plastic_area(b)
        rows.append({"probe": f"plastic_area@{a.t:.6g}", "measure": "zone area",
                     "relative_error": (sa - sb) / sb if sb > 0 else (0.0 if sa == 0 else float("inf")),
                     "smfem_peak": sa, "reference_peak": sb})
    return pd.DataFrame(rows)


def _histories_figure(case, s, r, path: Path) -> None:
    names = list(s.history)
    fields = {p.name: p.field for p in case.probes}
    fig, axes = subplots(len(names), 1, figsize=(7, 2.3 * len(names)), squeeze=False, sharex=True)
    for ax, name in zip(axes[:, 0], names):
        ax.plot(1e3 * r.t, r.history[name], "k-", lw=1.2, label="reference FEM")
        ax.plot(1e3 * s.t, s.history[name], "C3--", lw=1.2, label="SMFEM")
        ax.set_ylabel(f"{name}, {case.unit_of(fields[name])}", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0, 0].legend(fontsize=8)
    axes[-1, 0].set_xlabel("t, ms")
    fig.suptitle(f"{case.name}: SMFEM against the reference FEM", fontsize=10)
    fig.tight_layout()
    save(fig, path)


def compare(smfem_case, reference_case, out: Path, progress=None) -> tuple[pd.DataFrame, dict]:
    """Run both solvers, write their files and the comparison into ``out``; return the table
    and each solver's CPU time (s, by solver name; model building and time stepping)."""
    results = {}
    for label, case in ((SMFEM, smfem_case), (REFERENCE, reference_case)):
        wall0 = time.perf_counter()
        results[label] = solve(label, case, progress=progress, fields=True)
        write_run(out / label, case, label, results[label], time.perf_counter() - wall0)
    s, r = results[SMFEM], results[REFERENCE]
    table = comparison_table(s, r)
    table.to_csv(out / "comparison.csv", index=False, float_format="%.6g")
    _histories_figure(smfem_case, s, r, out / "histories.png")
    if s.snapshots and r.snapshots:
        plastic_zones({"SMFEM": s.snapshots, "reference FEM": r.snapshots}, out / "plastic_zones.png",
                      f"{smfem_case.name}: plastic zones (equivalent plastic strain >= 0.1 %)", smfem_case)
    return table, {label: result.cpu_time_s for label, result in results.items()}
