"""Figures of one case (matplotlib, Agg): the work-precision diagram and the probe histories."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .analysis import CaseAnalysis  # noqa: E402
from .metrics import TOLERANCE  # noqa: E402
from .plan import REF2D, REF3D, SMFEM  # noqa: E402
from .references import published_points, theory_curves  # noqa: E402

STYLE = {SMFEM: dict(color="C0", marker="o"), REF2D: dict(color="C1", marker="s"), REF3D: dict(color="C2", marker="^")}
LABEL = {SMFEM: "SMFEM", REF2D: "reference FEM 2D", REF3D: "reference FEM 3D"}


def work_precision(an: CaseAnalysis, path: Path) -> Path:
    """Error against CPU time, log-log, one line per solver, the tolerance as a dashed line."""
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for solver, s in an.solvers.items():
        pts = [(c, e, lab) for c, e, lab in zip(s.cpu, s.error, s.labels) if math.isfinite(e) and e > 0]
        if not pts:
            ax.plot([], [], ls="none", **STYLE[solver], label=f"{LABEL[solver]}: {s.status}")
            continue
        c, e, labels = zip(*pts)
        ax.plot(c, e, **STYLE[solver], label=LABEL[solver])
        for ci, ei, lab in pts:
            ax.annotate(lab, (ci, ei), textcoords="offset points", xytext=(4, 4), fontsize=7, color=STYLE[solver]["color"])
    ax.axhline(TOLERANCE, color="0.4", ls="--", lw=0.8, label=f"{100 * TOLERANCE:g} %")
    ax.set(xscale="log", yscale="log", xlabel="CPU time of the solve, s", ylabel="relative max-norm error")
    ax.set_title(f"{an.case.name}: error against CPU time\nreference: {an.reference.name if an.reference else 'none'}",
                 fontsize=9)
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _finest(runs):
    usable = [r for r in runs if r.usable]
    return usable[-1] if usable else None


def histories(an: CaseAnalysis, path: Path) -> Path:
    """Each probe over time: the reference, each solver's finest run, published points, theory."""
    probes = an.case.probe_names
    fig, axes = plt.subplots(len(probes), 1, figsize=(6.4, 2.3 * len(probes) + 0.6), sharex=True, squeeze=False)
    theory = theory_curves(an.case)
    for ax, probe in zip(axes[:, 0], probes):
        ref = an.reference
        if ref is not None and probe in ref.values:
            ax.plot(1e3 * ref.t, ref.values[probe], color="k", lw=2.2, alpha=0.35, label=ref.name)
        if theory is not None and (ref is None or theory.name != ref.name) and probe in theory.values:
            ax.plot(1e3 * theory.t, theory.values[probe], color="0.3", ls="--", lw=1, label=theory.name)
        for solver, runs in an.runs.series.items():
            run = _finest(runs)
            if run is not None:
                h = run.history
                ax.plot(1e3 * h["t"], h[probe], color=STYLE[solver]["color"], lw=1,
                        label=f"{LABEL[solver]} {run.label}")
        for pp in (p for p in published_points(an.case) if p.probe == probe):
            t, v = np.array([pt for pt in pp.points if pt[0] <= an.case.t_end]).reshape(-1, 2).T
            ax.plot(1e3 * t, v, "x", color="C3", ms=8, mew=2, label=f"published ({pp.source.split(',')[0]})")
        ax.set_ylabel(probe)
        ax.grid(True, lw=0.3, alpha=0.5)
        ax.legend(fontsize=6.5, loc="best")
    axes[-1, 0].set_xlabel("t, ms")
    fig.suptitle(f"{an.case.name}: probe histories", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path

