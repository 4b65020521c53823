"""The report's sections, built from the analyses; the template only lays them out.

A section is a title and a list of blocks (paragraph, sub-heading, list, table, figure, link).
:data:`SECTIONS` is the document's outline; :data:`EXTRA_SECTIONS` is the place for sections
added by later work (the stability study of issue 7 appends its builder there), rendered
after the case sections and before the methods.
"""

from __future__ import annotations

import base64
import os
import platform
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from .analysis import HEADLINE_MEASURE, CaseAnalysis
from .cache import code_version
from .metrics import TOLERANCE
from .plan import SMFEM
from .study import StudyResult


@dataclass
class Section:
    id: str
    title: str
    blocks: list = field(default_factory=list)
    css: str = ""


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


def p(text):
    return {"kind": "p", "text": text}


def h(text):
    return {"kind": "h", "text": text}


def items(values):
    return {"kind": "list", "entries": list(values)}


def table(df: pd.DataFrame):
    html = df.to_html(index=False, na_rep="", border=0, escape=True,
                      float_format=lambda x: f"{x:.4g}")
    return {"kind": "table", "html": html}


def figure(path: Path, caption: str):
    data = base64.b64encode(Path(path).read_bytes()).decode()
    return {"kind": "figure", "src": f"data:image/png;base64,{data}", "caption": caption}


def link(href: str, text: str):
    return {"kind": "link", "href": href, "text": text}


def overview(ctx: ReportContext) -> list[Section]:
    s = ctx.study
    missing = [an.case.name for an in ctx.analyses if not an.available]
    blocks = [
        p("How accurate and how fast SMFEM (the semi-analytic FEM: a finite-element cross-section with "
          "Fourier series along the third coordinate) is against the independent scikit-fem reference "
          "solver, in 2D (plane strain or axisymmetric) and in full 3D, on every verification case. "
          "Every run is what 'smfem run' does with the parameters shown; the time step is the case's in every "
          "run, so the errors measure the spatial discretization (CASES.md)."),
        items([
            f"settings: {ctx.settings}; {len(s.executed)} runs executed, {s.cached} taken from the cache; "
            f"study wall time {s.wall_time_s:.1f} s",
            f"machine: {platform.platform()}, {os.cpu_count()} CPUs, Python {platform.python_version()}",
            f"code versions (source hashes): smfem {code_version(SMFEM)}, reference {code_version('reference')}",
            "tables as CSV: tables/*.csv; per-run files (history.csv, summary.json): the run cache",
        ]),
    ]
    if missing:
        blocks.append(p("Not available (no solver can run them yet): " + ", ".join(missing) + "."))
    return [Section("overview", "Overview", blocks)]


HEADLINE_COLUMNS = {"best_error_pct": "best error, %", f"cpu_s_to_{100 * TOLERANCE:g}pct": f"CPU s to {100 * TOLERANCE:g} %",
                    "smfem_speedup": "SMFEM speed-up"}


def headline(ctx: ReportContext) -> list[Section]:
    return [Section("headline", f"Headline: CPU time to {100 * TOLERANCE:g} % error", [
        p(f"Error measure: {HEADLINE_MEASURE}, against the reference named in each row. The CPU time "
          f"to reach {100 * TOLERANCE:g} % is interpolated (log-log) on the work-precision curve; "
          "'<=' means the cheapest level was already below it, 'not reached' gives the best error. "
          "SMFEM's speed-up is that solver's CPU time to the tolerance over SMFEM's ('>' and '<' "
          "when one of them is a bound). CPU time is the solve's process time (model building, "
          "factorization, time stepping), one thread."),
        table(ctx.tables["headline"].rename(columns=HEADLINE_COLUMNS)),
    ])]


def _levels_table(an: CaseAnalysis) -> pd.DataFrame:
    e = an.errors
    if not len(e):
        return pd.DataFrame()
    e = e[e.headline]
    return (e.groupby(["solver", "level"], sort=False)
            .agg(n_dof=("n_dof", "first"), cpu_time_s=("cpu_time_s", "first"), status=("status", "first"),
                 err_max_pct=("err_max", lambda x: 100 * x.max()), err_l2_pct=("err_l2", lambda x: 100 * x.max()))
            .reset_index())


def _richardson_table(df: pd.DataFrame) -> pd.DataFrame:
    out = df[["solver", "probe", "h", "finest", "order", "extrapolated", "reference_peak"]].copy()
    out["finest vs extrapolated, %"] = 100 * df.finest_vs_extrapolated
    out["extrapolated vs reference, %"] = 100 * df.extrapolated_vs_reference
    return out


def _case(ctx: ReportContext, an: CaseAnalysis) -> Section:
    name, figs = an.case.name, ctx.figures.get(an.case.name, {})
    blocks = [p(an.case.title)]
    refused = [f"{s}: {v.status}: {v.message}" for s, v in an.solvers.items() if v.status != "ok"]
    if refused:
        blocks.append(items(refused))
    if not an.available:
        return Section(name, name, blocks, css="case")
    blocks.append(p(f"Reference: {an.reference.name if an.reference else 'none available'}."))
    if "work_precision" in figs:
        blocks.append(figure(ctx.out / figs["work_precision"], f"{name}: work-precision diagram"))
    ref = an.reference.name if an.reference else "none"
    blocks += [h(f"Errors per level (headline probes) against {ref}"), table(_levels_table(an))]
    if len(an.orders):
        blocks += [h(f"Observed orders (log-log fit of error against h) against {ref}"),
                   table(an.orders.drop(columns=["case", "reference"]))]
    if len(an.richardson):
        blocks += [h("Richardson extrapolation of each probe's peak value (three finest levels)"),
                   table(_richardson_table(an.richardson))]
    if len(an.published):
        finest = an.published.groupby("solver", sort=False)["level"].transform("last") == an.published["level"]
        blocks += [h(f"Against the published extrema ({an.published.source.iloc[0]}), finest level of each solver"),
                   table(an.published[finest].drop(columns=["case", "source"]))]
    if "histories" in figs:
        blocks.append(figure(ctx.out / figs["histories"], f"{name}: probe histories"))
    if "plastic_zones" in figs:
        blocks.append(figure(ctx.out / figs["plastic_zones"],
                             f"{name}: SMFEM plastic zones (equivalent plastic strain >= 0.1 %) at the paper's times"))
    if "field" in figs:
        blocks.append(figure(ctx.out / figs["field"], f"{name}: synthesized 3-D field of SMFEM at the final time"))
    if "vtu" in figs:
        blocks.append(link(figs["vtu"], f"{figs['vtu']} (open in ParaView)"))
    return Section(name, f"Case {name}", blocks, css="case")


def cases(ctx: ReportContext) -> list[Section]:
    return [_case(ctx, an) for an in ctx.analyses]


def methods(ctx: ReportContext) -> list[Section]:
    return [Section("methods", "Methods", [items([
        "Relative max-norm error: max|a - b| / max|b| over the common time window, the run's history "
        "linearly interpolated to the reference's times. Relative L2 error: the same with the "
        "time integrals of (a - b)^2 and b^2.",
        "Reference, in order of preference: an analytic history where it is exact for the case as set up "
        "(the 1-D rod theory for nu = 0), a published history (none of the cases has one: the dome's "
        "published data are three extrema read off a curve, compared in their own table), then the "
        "finest reference-FEM run, finer than every level of the series.",
        "Published extrema: the computed extremum of the same kind between the midpoints to the "
        "neighbouring published times.",
        "rod_impact: every history is seen through a moving average over 2R/c (the time a wave takes "
        "to cross the rod's diameter) before it is compared: the ringing behind the wave front is "
        "mesh-dependent in both solvers (29-38 % in L2 between refinements).",
        "Observed order: slope of log(error) against log(h), h = 1/refine, 1/harmonics or dt, whichever "
        "varies along the series.",
        "Richardson: q(h) = q* + C h^p through the three finest levels of a series (any ratios of h), "
        "for each probe's peak value (the signed value of largest magnitude).",
        "Runs are cached by case, resolved parameters, solver and a hash of the solver's source files: "
        "a rebuilt report reuses every finished run.",
    ])])]


#: sections added by later work; each is ``builder(ctx) -> list[Section]`` (issue 7: stability)
EXTRA_SECTIONS: list = []
#: the document's outline
SECTIONS = [overview, headline, cases]


def build_sections(ctx: ReportContext) -> list[Section]:
    return [s for builder in [*SECTIONS, *EXTRA_SECTIONS, methods] for s in builder(ctx)]
