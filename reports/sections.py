"""The report's sections, built from the analyses; the template only lays them out.

A section is a title and a list of blocks (:mod:`reports.blocks`); :mod:`reports.outline` lists
the builders in the document's order. A scene's section: :mod:`reports.scene`.
"""

from __future__ import annotations

import os
import platform
from dataclasses import dataclass, field
from pathlib import Path

from .analysis import FAMILIES, HEADLINE_MEASURE, CaseAnalysis
from smfem.studies.calibration import FLOOR, SHARPNESS
from smfem.studies.cache import code_version
from smfem.studies.effectivity import BAND
from smfem.studies.effectivity import summary as effectivity_summary
from smfem.studies.metrics import TARGETS, TRUTH_MARGIN
from smfem.studies.plan import REFERENCE, SMFEM
from smfem.studies.study import StudyResult
from smfem.studies.timing import TimingRule
from .blocks import Section, figure, h, items, p, table
from .scene import scene
from .timing import timed_runs
from .verdict import verdict

#: the quick settings' timing rule, which the headline's reading says
QUICK_TIMING = TimingRule.of(False)


@dataclass
class ReportContext:
    """Everything a section builder may use. ``figures[case]`` maps a figure's name
    (``work_precision``, ``histories``, ``plastic_zones``, ``field``) to its PNG and ``vtu`` to
    the copied fields file, relative to ``out``."""

    analyses: list[CaseAnalysis]
    tables: dict
    figures: dict
    study: StudyResult
    settings: str
    out: Path
    #: figures over every case (``effectivity``), relative to ``out``
    overall: dict = field(default_factory=dict)


def overview(ctx: ReportContext) -> list[Section]:
    s = ctx.study
    missing = [an.case.name for an in ctx.analyses if not an.available]
    blocks = [
        p("How accurate and how fast SMFEM (the semi-analytic FEM: a finite-element cross-section with "
          "Fourier series along the third coordinate) is against the independent scikit-fem reference "
          "solver, in 2D (plane strain or axisymmetric) and in full 3D, and against CalculiX (where ccx is "
          "installed) on the reference's mesh, on every verification case. "
          "Every run is what 'smfem run' does with the parameters shown. Errors are total errors, against a "
          "truth per case converged in mesh, harmonics and time, with its own uncertainty ('smfem truth'; "
          "the scenes at their own parameters use the truths stored in truths/, made once by "
          "'smfem truth CASE --full' and calibrated against a second, independent path); "
          "each solver's series spans the mesh and the time step, so its work-precision front answers "
          "'how close to the true solution, for what cost'. The paper's question, the difference between "
          "solvers at one shared time step (the spatial discretization only), is answered beside it."),
        items([
            f"settings: {ctx.settings}; {len(s.executed)} runs executed, {s.cached} taken from the cache; "
            f"study wall time {s.wall_time_s:.1f} s",
            f"machine: {platform.platform()}, {os.cpu_count()} CPUs, Python {platform.python_version()}",
            f"code versions (source hashes): smfem {code_version(SMFEM)}, reference {code_version(REFERENCE)}",
            "tables as CSV: tables/*.csv; per-run files (history.csv, summary.json): the run cache",
            *_timed(ctx.tables.get("timing")),
        ]),
    ]
    if missing:
        blocks.append(p("Not available (no solver can run them yet): " + ", ".join(missing) + "."))
    return [Section("overview", "Overview", blocks)]


def verdict_section(ctx: ReportContext) -> list[Section]:
    """The answer first: per scene, where SMFEM stands at equal total error (:mod:`reports.verdict`)."""
    return [Section("verdict", "Verdict", [
        items(verdict(ctx.tables["headline"])),
        p(f"Total error: {HEADLINE_MEASURE}, against each scene's truth; speed-ups are CPU-time ratios at "
          "the same error, on one thread, of each run's minimum over the timing pass's repeats ('more than': the "
          "other solver does not reach the target in this study). Each scene's section has every solver's cost and "
          "its work-precision diagram."),
    ])]


def headline(ctx: ReportContext) -> list[Section]:
    """How to read every scene's headline rows, said once; the rows are in each scene's section."""
    names = " and ".join(f"{100 * t:g} %" for t in TARGETS)
    targets = "; ".join(f"{f}: " + " and ".join(f"{100 * t:g} %" for t in ts) for f, (_, ts) in FAMILIES.items())
    return [Section("headline", f"Headline: CPU time to {names} total error", [
        p(f"Each scene's section opens with its verdict, its work-precision diagram and its headline rows, one per "
          f"solver. Error measure: {HEADLINE_MEASURE}, against the scene's truth (named under its rows, with its "
          "uncertainty in the same measure). The CPU time is that of the cheapest run whose error is "
          "within the target, with its settings; 'not reached' gives the best error. A target below "
          f"{TRUTH_MARGIN:g} times the truth's uncertainty is 'truth not fine enough': no run can be said to reach it. "
          "SMFEM's speed-up is that solver's CPU time over SMFEM's at the same target ('>' when the solver does not "
          "reach it even at its dearest run, '<' when SMFEM does not). A solver of several series is one row: "
          "CalculiX's procedures, and the 3D reference's implicit and explicit engines; at each target the row "
          "holds the cheapest of its series, named in the cell, and the speed-up is over that one. CPU time is "
          "the solve's process time (model building, factorization, time stepping), one thread. The runs within a "
          "target were timed again after the study, one at a time with nothing else running, SMFEM's and the "
          "other's by turns (the timing pass, "
          "tables/timing.csv): their CPU time is the minimum over the repeats and each speed-up a ratio of minima, "
          "with its range over the repeats beside it (the other's fastest over SMFEM's slowest to the other's "
          "slowest over SMFEM's fastest). On the quick settings a run whose study shot took over "
          f"{QUICK_TIMING.kept_s:g} s keeps that shot (0 repeats in tables/timing.csv), and on any settings one whose "
          f"shot is over {QUICK_TIMING.rivals:g} times its rival's (SMFEM's other element, the other engine or procedure), which "
          "cannot decide its row's cost, keeps it outside the pass. A reason in a cell is a numbered note under its "
          "table."),
        p("Stresses and plastic strains have rows of their own in each scene, outside the headline measure: each "
          "family judged on its own (max over its probes of the relative max-norm error) and against its own "
          f"targets ({targets}): a stress at a wave front or a plastic strain at a yielding point converges more "
          "slowly than a displacement. Where every solver gives the same answer for a probe group (no converged "
          "truth, say), it is one row."),
        items(["every scene and solver: tables/headline.csv and tables/stresses.csv",
               "every run, order, published extremum and the truth per probe: the appendix, and tables/*.csv"]),
    ], appendix=_timing_table(ctx.tables.get("timing")))]


def _timed(timing) -> list[str]:
    """The timing pass in one line (none without a pass)."""
    if timing is None or not len(timing):
        return []
    runs = timed_runs(timing)
    return [f"timing pass: {len(runs)} runs behind the headline timed again, {int(runs.repeats.sum())} repeats "
            f"(tables/timing.csv)"]


def _timing_table(timing) -> list:
    """The timing pass's repeats per decisive run (none without a pass)."""
    if timing is None or not len(timing):
        return []
    shown = timing.assign(target=[f"{100 * t:g} %" for t in timing.target])
    return [h("The timing pass: the runs within each target timed again (tables/timing.csv)"),
            table(shown.round({"cpu_min_s": 4, "cpu_median_s": 4, "cpu_max_s": 4, "study_cpu_s": 4}))]


def estimates(ctx: ReportContext) -> list[Section]:
    """Each run's own error estimate (what 'smfem run' prints) against its actual error."""
    eff = ctx.tables.get("effectivity")
    if eff is None or not len(eff):
        return []
    shown = eff.assign(**{c: 100 * eff[c] for c in eff.columns if c == "actual" or c.startswith("estimate")})
    shown = shown.assign(companions_per_run=eff.companions_cpu_s / eff.run_cpu_s)
    columns = ["case", "solver", "setting", "level", "probe", "estimate", "actual", "effectivity",
               *[c for c in eff.columns if c.startswith(("estimate_", "order_"))], "measured_upward",
               "companions_per_run"]
    blocks = [
        p("Every 'smfem run' states its own error: companion runs on a mesh half as fine, and on that mesh at "
          "twice and four times the step (and, for SMFEM, half and a quarter of the harmonics), turned into the "
          "run's error by Richardson's rule at the order observed from the three levels (smfem/runs/estimate.py). "
          "Here each scene's SMFEM and 2D reference runs at the defaults, at twice the mesh and at half the step "
          "are estimated so, and the estimate is set against the actual error from the truth. An honest "
          f"estimate has an effectivity (estimate / actual) between {BAND[0]:g} and {BAND[1]:g}; it is judged "
          f"where the actual error exceeds {TRUTH_MARGIN:g} truth uncertainties. Errors in %; "
          "companions_per_run: the companions' CPU over the run's."),
        items([effectivity_summary(eff)]),
    ]
    if ctx.overall.get("effectivity"):
        blocks.append(figure(ctx.out / ctx.overall["effectivity"], "Effectivity per scene, solver and setting"))
    return [Section("estimates", "Error estimates against the truth", blocks,
                    appendix=[table(shown[columns].round(4))])]


def code_verification(ctx: ReportContext) -> list[Section]:
    """Each solver's observed orders on the manufactured motions (``smfem verify``): the code
    verification that comes before the solution verification (truths) and the comparison."""
    if ctx.settings not in ("quick", "full"):  # the tests' tiny study leaves it out
        return []
    from . import verification

    rows = verification.cached(ctx.out / "runs", quick=ctx.settings != "full")
    figures = verification.write(rows, ctx.out, "tables/code_verification.csv")
    off = rows[~rows.within]
    blocks = [
        p("Before any run is compared with a truth, each solver is shown to solve the equations it claims to: on a "
          "ring and a prism whose exact motion is chosen (a bubble over the section, fixed on its edges, times "
          "harmonics 0-3 along x3, times a function of time; E and rho varying as 1 + 0.3 cos 2 k x3, which "
          "couples the harmonics), the body force that makes it exact is derived symbolically "
          "(cases/manufactured.py), and the error against the exact motion falls at the order of each scheme: "
          "space by each solver's relative L2 error over the body on refined meshes, harmonics resolved, with the "
          "time function t^2 that Newmark integrates exactly; time by successive halvings of the step with "
          "1 - cos 3t, at the displacement probes (the mesh's error cancels); harmonics by leaving one out. "
          "Theory: in L2, SMFEM's bilinear moment-scheme element 2 and the reference's quadratic element 3; "
          "Newmark's average acceleration 2."),
        items(verification.summary(rows)),
        p(f"{len(rows) - len(off)} of {len(rows)} orders within {verification.ORDER_TOLERANCE:g} of the "
          "theory." + ("" if off.empty else " Outside: " + "; ".join(
              f"{r.solver} {r.body} {r.parameter} {r.probe} ({r.observed_order:.2f})" for r in off.itertuples()))),
        *[figure(path, f"Code verification: {path.stem.removeprefix('verification-')}") for path in figures],
    ]
    return [Section("code-verification", "Code verification: manufactured solutions", blocks,
                    appendix=[table(rows.drop(columns=[c for c in ("differences", "too_few_over_all") if c in rows]))])]


def cases(ctx: ReportContext) -> list[Section]:
    return [scene(ctx, an) for an in ctx.analyses]


def methods(ctx: ReportContext) -> list[Section]:
    return [Section("methods", "Methods", [items([
        "Relative max-norm error: max|a - b| / max|b| over the common time window, on the coarser of the two "
        "time grids (time steps are halvings of each other, so a run is compared at its own steps). Relative "
        "L2 error: the same with the time integrals of (a - b)^2 and b^2.",
        "Truth, linear scenes homogeneous along x3 (dome, thick cylinder): the reference's Fourier-harmonic "
        "model (quadratic elements on the cross-section, one 2D problem per harmonic) integrated exactly in "
        "time by modal superposition; its spatial error from a ladder of three meshes and its Fourier "
        "truncation from a ladder of three harmonic counts, each by the observed order of the three levels "
        "(grid convergence index 1.25 |q_h - q_2h| / (2^p - 1), p at most 2), plus the modes left out of the "
        "largest harmonics.",
        "Truth, plastic and contact scenes (notched cylinder, notched strip, rod): the reference's mesh and "
        "quadratic element integrated by central differences on an HRZ-lumped mass at half the critical step "
        "2 / omega_max (the step halves with the mesh, so space and time converge together; radial return at "
        "every step; the rod's wall a kinematic constraint), over meshes r2, r4, r8. Richardson's extrapolation "
        "at the ladder's observed order is the truth where the interleaved pair r3, r6, extrapolated at the same "
        "order, confirms it (uncertainty: 1.25 times the distance between the two extrapolations), else the "
        "finest mesh with its grid convergence index. The notched scenes use the B-bar form of the element (the "
        "volumetric strain projected on {1, x, y} per element, free of locking under plastic flow).",
        "Stored truths: 'smfem truth CASE --full' makes a scene's truth at its own parameters once (tens of "
        "minutes to hours) and keeps it in smfem/truths/CASE, keyed by a hash of the case's definition and the truth "
        "method; a report uses it while the key matches and otherwise computes a quick truth (the same modal "
        "method on coarser ladders, or the 2D reference at three halvings of the time step with a mesh "
        "correction) and says so. Each stored truth is calibrated against a second, independent path (the "
        "explicit reference for a modal truth, the other element for the notched scenes, implicit Newmark with "
        "Lagrange-multiplier contact for the rod).",
        "Calibration (a stored truth's table in the appendix): covered: the distance between the truth and the "
        "second path is within the sum of their uncertainties; sharp: the truth's uncertainty is at most "
        f"{SHARPNESS:g} times the distance (or {100 * FLOOR:.3g} %); widened: the truth's own uncertainty did not "
        "cover the distance, so it is stated as the distance plus the second path's uncertainty.",
        "Same-dt comparison (the paper's): runs at the case's time step against the finest reference run "
        "at that time step, or an analytic history where it is exact (the 1-D rod theory for nu = 0).",
        "Published extrema: the computed extremum of the same kind between the midpoints to the "
        "neighbouring published times.",
        "rod_impact: every history is seen through a triangular window 2R/c wide (two moving averages R/c "
        "long; 2R/c is the time a wave takes to cross the rod's diameter), each on its own time grid, before "
        "it is compared, truth uncertainties included: the ringing behind the wave front is mesh-dependent in "
        "every model.",
        "CalculiX (ccx, one thread): one run per case at the case's settings in 2D, on the reference FEM's "
        "mesh with serendipity elements (CPE8 / CAX8), from the deck 'smfem export' writes; Newmark with "
        "ALPHA = 0 at the case's dt (plastic scenes: ccx's own increments of at most dt, interpolated onto "
        "the dt grid); its plastic strains are nodal PEEQ (accumulated), not the cases' sqrt(2/3 eps_p:eps_p). "
        "Its CPU time is ccx's own. A scene with a rigid wall is not solved (the scene's rows say why).",
        "The 3D reference's explicit engine (the full settings' series 'reference FEM 3D, explicit'): the implicit "
        "engine's 27-node mesh and element, central differences on the HRZ-lumped mass at half the mesh's "
        "critical step (its own Courant limit: the case's dt is its output interval only), so its levels are "
        "meshes. The headline's 3D row is the cheaper engine at each target; each engine keeps its own runs "
        "in the appendix and tables/fronts.csv.",
        "Observed order: slope of log(error) against log(h), h = dt at a fixed mesh, or dof^(-1/2) at the "
        "case's time step. An order near zero or negative means the refined parameter does not limit the "
        "error there (at a fixed mesh, the space error dominates; the orders table says so per row).",
        "Runs are cached by case, resolved parameters, solver and a hash of the solver's source files: "
        "a rebuilt report reuses every finished run.",
    ])])]

