"""Figures of one case (matplotlib, Agg): the work-precision diagram and the probe histories."""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np
from matplotlib.ticker import NullFormatter, NullLocator

from smfem.runs.figures import place_labels, save, subplots
from smfem.runs.registry import lookup

from .analysis import CaseAnalysis
from smfem.studies.effectivity import BAND
from smfem.studies.metrics import TARGETS, TRUTH_MARGIN, smoothed
from .references import published_points, theory_curves

#: characters per line of a figure's title (a 6.4 in wide figure at 8 pt)
TITLE_WIDTH = 90


def work_precision(an: CaseAnalysis, path: Path) -> Path:
    """Total error against CPU time, log-log: every run as a point, each solver's front as a
    line with its points labelled, the targets dashed, and the band below three times the
    truth's uncertainty, where no error can be measured, shaded."""
    fig, ax = _axes(4.9)
    labels = []
    for solver, s in an.solvers.items():
        entry = lookup(solver)
        pts = s.points[np.isfinite(s.points.total) & (s.points.total > 0)] if len(s.points) else s.points
        if not len(pts):
            ax.plot([], [], ls="none", **entry.style, label=f"{entry.label}: {s.status}")
            continue
        ax.plot(pts.cpu, 100 * pts.total, ls="none", alpha=0.35, **entry.style)
        front = pts.set_index("label").loc[[lab for lab in s.front if lab in set(pts.label)]]
        ax.plot(front.cpu, 100 * front.total, **entry.style, label=f"{entry.label} (front)")
        labels.append((front.cpu, 100 * front.total, front.index, entry.color))
    for target in TARGETS:
        ax.axhline(100 * target, color="0.4", ls="--", lw=0.8)
    u = an.truth_uncertainty
    if math.isfinite(u) and u > 0:
        ax.axhspan(1e-10, 100 * TRUTH_MARGIN * u, color="0.85", zorder=0,
                   label=f"below {TRUTH_MARGIN:g} x truth uncertainty ({100 * u:.2g} %)")
    ax.set(xlabel="CPU time of the solve, s", ylabel="total error (relative max-norm), %")
    if not labels:
        ax.text(0.5, 0.5, "no run compared with a truth", ha="center", transform=ax.transAxes)
        return _save(fig, ax, path, f"{an.case.name}: no truth")
    _log_axes(ax)
    ymin = min([s.points.total[s.points.total > 0].min() for s in an.solvers.values()
                if len(s.points) and (s.points.total > 0).any()] or [min(TARGETS)])
    bottom = 0.5 * min(ymin, TRUTH_MARGIN * u if math.isfinite(u) and u > 0 else ymin, min(TARGETS))
    ax.set_ylim(100 * bottom, max(ax.get_ylim()[1], 200 * max(TARGETS)))  # the targets and their labels inside
    # the targets named on the right-hand axis, outside the plot: a label inside could lie on a
    # run's marker, and where the runs fall depends on the machine's CPU times. Made once the
    # scale is log: setting the scale resets a secondary axis's ticks (it showed "10^0", not "1 %")
    named = ax.secondary_yaxis("right")
    named.yaxis.set_minor_locator(NullLocator())
    named.set_yticks([100 * t for t in TARGETS], labels=[f"{100 * t:g} %" for t in TARGETS])
    named.tick_params(labelsize=7, labelcolor="0.3", length=0)
    return _save(fig, ax, path, f"{an.case.name}: total error against CPU time\ntruth: {an.truth.name}", labels)


#: the report's figures' width, and about the width of a character of a 7-point name (inches)
FIGURE_WIDTH_IN = 6.4
NAME_CHAR_IN = 0.06


def _axes(height: float):
    # the legend goes below the axes, where it cannot cover a point or its label
    return subplots(figsize=(FIGURE_WIDTH_IN, height), layout="constrained")


def _log_axes(ax) -> None:
    """Log scales whose limits reach the powers of ten around the data, labelled at those powers
    only: on a range of a decade or two matplotlib labels minor ticks too (2 x 10^-2, 3 x 10^-2),
    and in a small panel those run into each other."""
    ax.set(xscale="log", yscale="log")
    for get, put, axis in ((ax.get_xlim, ax.set_xlim, ax.xaxis), (ax.get_ylim, ax.set_ylim, ax.yaxis)):
        lo, hi = get()
        put(10 ** math.floor(math.log10(lo)), 10 ** math.ceil(math.log10(hi)))
        axis.set_minor_formatter(NullFormatter())


def _label_points(ax, labels) -> None:
    """Each solver's points labelled clear of each other (those with no free spot left out, and
    said so)."""
    if labels:
        ax.figure.canvas.draw()  # once: the labels take no part in the layout
    left_out = sum(place_labels(ax, x, y, names, color, drawn=True) for x, y, names, color in labels)
    if left_out:
        ax.annotate(f"{left_out} point labels left out (no free spot)", (0.01, 0.01), xycoords="axes fraction",
                    fontsize=6, color="0.4")


def _save(fig, ax, path: Path, title: str, labels=()) -> Path:
    # long truth names wrap instead of running off both sides
    ax.set_title("\n".join(textwrap.fill(line, TITLE_WIDTH) for line in title.splitlines()), fontsize=8)
    ax.grid(True, which="both", lw=0.3, alpha=0.5)
    if ax.get_legend_handles_labels()[0]:
        fig.legend(loc="outside lower center", ncols=2, fontsize=7)
    _label_points(ax, labels)  # last: the layout is final, the labels land where they are checked
    return save(fig, path)


def spatial_precision(an: CaseAnalysis, path: Path) -> Path:
    """The paper's comparison: error against the same-dt reference, runs at the case's dt."""
    fig, ax = _axes(4.6)
    labels = []
    for solver, s in an.solvers.items():
        pts = s.points[np.isfinite(s.points.spatial) & (s.points.spatial > 0)] if len(s.points) else s.points
        if not len(pts):
            continue
        entry = lookup(solver)
        ax.plot(pts.cpu, 100 * pts.spatial, **entry.style, label=entry.label)
        labels.append((pts.cpu, 100 * pts.spatial, pts.label, entry.color))
    ax.set(xlabel="CPU time of the solve, s", ylabel="relative max-norm difference, %")
    if labels:
        _log_axes(ax)
    return _save(fig, ax, path, f"{an.case.name}: at the case's dt, against "
                 f"{an.reference.name if an.reference else 'none'}\n(spatial discretization only, as the paper compared)",
                 labels)


def _most_accurate(an: CaseAnalysis, solver: str, runs):
    """The solver's run with the smallest total error (else its last usable run)."""
    s = an.solvers.get(solver)
    if s is not None and len(s.points) and s.points.total.notna().any():
        label = s.points.label.iloc[int(np.nanargmin(s.points.total.to_numpy()))]
        return next(r for r in runs if r.label == label)
    usable = [r for r in runs if r.usable]
    return usable[-1] if usable else None


def histories(an: CaseAnalysis, path: Path) -> Path:
    """Each probe over time: the truth, each solver's most accurate run, published points, theory;
    where the case compares through a window (the rod), every curve as the comparison sees it."""
    probes = an.case.probe_names
    fig, axes = subplots(len(probes), 1, figsize=(6.4, 2.3 * len(probes) + 0.6), sharex=True, squeeze=False)
    theory = theory_curves(an.case)
    window = an.case.references.get("comparison_window_s", 0.0)
    seen = lambda t, x: smoothed(np.asarray(x, float), np.asarray(t, float), window)
    fields = {p.name: p.field for p in an.case.probes}
    for ax, probe in zip(axes[:, 0], probes):
        truth = an.truth
        if truth is not None and probe in truth.values and truth.converged(probe):  # no curve for a non-truth
            ax.plot(1e3 * truth.t, seen(truth.t, truth.values[probe]), color="k", lw=2.2, alpha=0.35, label="truth")
        if theory is not None and probe in theory.values:
            ax.plot(1e3 * theory.t, seen(theory.t, theory.values[probe]), color="0.3", ls="--", lw=1, label=theory.name)
        for solver, runs in an.runs.series.items():
            run = _most_accurate(an, solver, runs)
            if run is not None:
                h, entry = run.history, lookup(solver)
                ax.plot(1e3 * h["t"], seen(h["t"], h[probe]), color=entry.color, lw=1,
                        label=f"{entry.label} {run.label}")
        for pp in (p for p in published_points(an.case) if p.probe == probe):
            t, v = np.array([pt for pt in pp.points if pt[0] <= an.case.t_end]).reshape(-1, 2).T
            ax.plot(1e3 * t, v, "x", color="C3", ms=8, mew=2, label=f"published ({pp.source.split(',')[0]})")
        ax.set_ylabel(f"{probe}, {an.case.unit_of(fields[probe])}")
        ax.grid(True, lw=0.3, alpha=0.5)
        ax.legend(fontsize=6.5, loc="best")
    axes[-1, 0].set_xlabel("t, ms")
    fig.suptitle(f"{an.case.name}: probe histories"
                 + (f", through a {1e6 * window:.3g} us window as compared" if window else ""), fontsize=10)
    fig.tight_layout()
    return save(fig, path)



#: marker per estimated setting (:func:`smfem.studies.effectivity.settings`); the colour is the solver's
SETTING_MARKER = {"defaults": "o", "refine 2": "s", "dt/2": "^"}


def effectivity(table, path: Path) -> Path:
    """Every judged estimate's effectivity (estimate / actual error) per scene, solver and
    setting, on a log axis with the honest band shaded."""
    fig, ax = _axes(4.2)
    judged = table.dropna(subset=["effectivity"])
    names = list(dict.fromkeys(table.case))
    solvers = list(dict.fromkeys(table.solver))
    ax.axhspan(*BAND, color="0.85", zorder=0, label=f"honest: {BAND[0]:g} ... {BAND[1]:g}")
    ax.axhline(1.0, color="0.5", lw=0.8)
    for k, solver in enumerate(solvers):
        entry = lookup(solver)
        for j, (setting, marker) in enumerate(SETTING_MARKER.items()):
            rows = judged[(judged.solver == solver) & (judged.setting == setting)]
            x = [names.index(c) + 0.3 * (k - (len(solvers) - 1) / 2) + 0.07 * (j - 1) for c in rows.case]
            ax.plot(x, rows.effectivity, ls="none", marker=marker, color=entry.color, ms=5, mfc="none",
                    label=f"{entry.label}, {setting}")
    # level where each name fits its slot, else upright: a slanted name's box reaches over its
    # neighbour's (layered_cylinder, layered_cylinder_pulse); an upright one shortens the axes
    level = max(map(len, names)) * NAME_CHAR_IN <= FIGURE_WIDTH_IN * 0.8 / len(names)
    ax.set_xticks(range(len(names)), names, fontsize=7, rotation=0 if level else 90)
    ax.set(yscale="log", ylabel="estimate / actual error, -", xlim=(-0.6, len(names) - 0.4))
    lo, hi = ax.get_ylim()
    ax.set_ylim(min(lo, 0.1), max(hi, 10))
    return _save(fig, ax, path, "Each run's error estimate against its actual error (displacement and velocity "
                 "probes whose truth is fine enough)")


#: what each verification parameter is plotted against
_STEP = {"space": ("refine", "mesh size h / h(refine 1), -"), "time": ("dt", "time step dt, -")}


def verification_orders(table, solver: str, path: Path) -> Path:
    """Code verification of one solver: per parameter, log-log per body, the L2 error against the
    mesh size (space) and the largest step-halving difference over the displacement probes
    against the step (time), with the theory's slope dashed through the finest point."""
    rows = table[(table.solver == solver) & table.parameter.isin(list(_STEP))]
    params = [p for p in _STEP if p in set(rows.parameter)]
    fig, axes = subplots(1, len(params), figsize=(3.4 * len(params) + 0.6, 3.3), squeeze=False)
    for ax, parameter in zip(axes[0], params):
        key, xlabel = _STEP[parameter]
        ticks = set()
        for k, (body, group) in enumerate(rows[rows.parameter == parameter].groupby("body", sort=False)):
            x = np.array([float(level.split("=")[1]) for level in group.levels.iloc[0].split(" ")])
            x = 1.0 / x if key == "refine" else x
            column = "differences" if parameter == "time" else "errors"
            y = np.max([[float(v) for v in text.split()] for text in group[column]], axis=0)
            x = x[1:] if parameter == "time" else x  # a difference belongs to the finer of its pair
            ticks |= set(x)
            lo, hi = group.observed_order.min(), group.observed_order.max()
            ax.loglog(x, y, marker="os"[k % 2], color=f"C{k}", label=f"{body}: {lo:.2f}" + ("" if lo == hi else f"-{hi:.2f}"))
            theory = group.theoretical_order.iloc[0]
            ax.loglog(x, y[-1] * (x / x[-1]) ** theory, ls="--", color=f"C{k}", lw=0.8)
        for axis in (ax.xaxis, ax.yaxis):  # a short log range labels its minor ticks, one over another
            axis.set_minor_formatter(NullFormatter())
        ax.set_xticks(sorted(ticks), [f"{v:g}" for v in sorted(ticks)])  # the levels themselves
        ax.set_xlabel(xlabel)
        ax.set_ylabel("relative L2 error, -" if parameter == "space" else "step-halving difference, -")
        ax.set_title(f"{parameter} (dashed: order {rows[rows.parameter == parameter].theoretical_order.iloc[0]:g})",
                     fontsize=8)
        ax.legend(fontsize=7, title="observed order", title_fontsize=7)
        ax.grid(True, which="both", lw=0.3)
    fig.suptitle(f"Code verification, {lookup(solver).label}: manufactured motions", fontsize=9)
    fig.tight_layout()
    return save(fig, path)
