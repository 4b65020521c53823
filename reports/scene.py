"""A scene's section: its verdict, its work-precision figure and its headline rows first (a page
or two), its other figures after them, its per-run and per-probe tables in the appendix."""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd

from smfem.runs.registry import lookup
from smfem.studies.jobs import NOT_INSTALLED, OK

from .analysis import FAMILIES, CaseAnalysis
from .blocks import Section, figure, figures, h, items, link, p, table
from .compact import merged
from .tables import RANGE, truth_table
from .verdict import sentence

#: the solver cell of a row that every solver's answer shares
EVERY_SOLVER = "every solver"


def cost_labels(df: pd.DataFrame) -> dict:
    """Readable names of a costs table's columns (any targets)."""
    out = {"best_error_pct": "best total error, %"}
    for column in df.columns:
        for prefix, text in (("cpu_s_to_", "CPU s to {} (settings)"), ("smfem_speedup_", "SMFEM speed-up at {}")):
            if column.startswith(prefix):
                target = column[len(prefix):].removesuffix(RANGE).replace("pct", " %")
                out[column] = "its range over repeats" if column.endswith(RANGE) else text.format(target)
    return out


def _costs(rows: pd.DataFrame, first: list[str]) -> pd.DataFrame:
    """``first`` columns, then the CPU time to each target and SMFEM's speed-up at each (those the
    rows fill), then the best error."""
    said = [c for c in rows.columns if (rows[c].notna() & (rows[c].astype(str) != "")).any()]
    cpu = [c for c in said if c.startswith("cpu_s_to_")]
    speed = [c for c in said if c.startswith("smfem_speedup_")]
    return rows[[*first, *cpu, *speed, "best_error_pct"]]


def headline_rows(head: pd.DataFrame, case: str) -> pd.DataFrame:
    """The scene's rows of ``tables/headline.csv``: a solver each, its costs and its best error."""
    rows = head[head.case == case]
    return _costs(rows, ["solver"]).rename(columns=cost_labels(rows))


def family_rows(families: pd.DataFrame, case: str, solvers) -> pd.DataFrame:
    """The scene's rows of ``tables/stresses.csv`` for ``solvers`` (those that ran: the others'
    reasons are in the headline rows), one per probe group where every solver gives the same
    answer (no converged truth, say), else one per solver, the group named in its first row."""
    rows = families[(families.case == case) & families.solver.isin(solvers)] if "case" in families else families
    if not len(rows):
        return rows
    rows = _costs(rows.assign(probes=rows.family + " (" + rows.probes + ")"), ["probes", "solver"])
    rows = merged(rows, "solver", ["probes"], EVERY_SOLVER)
    return rows.assign(probes=rows.probes.where(~rows.probes.duplicated(), "")).rename(columns=cost_labels(rows))


def _uncertainty(u: float) -> str:
    return f"{100 * u:.2g} %" if math.isfinite(u) else "not converged (singular probes: the appendix's truth table)"


def _truth(an: CaseAnalysis) -> str:
    """The truth in one sentence: what it is, its cost, its uncertainty in each measure."""
    t = an.truth
    if t is None:
        return "No truth: " + ("no truth plan" if an.runs.study.truth is None else
                               "a run it needs has no history") + "."
    measures = [f"headline measure {_uncertainty(an.truth_uncertainty)}",
                *(f"{family} {_uncertainty(an.uncertainty_of(family))}" for family in FAMILIES if an.probes_of(family))]
    return (f"Truth: {t.name}; {t.source}. CPU time {t.cpu_time_s:.3g} s over {len(t.levels)} runs. "
            f"Its uncertainty: {', '.join(measures)}.")


def _levels_table(an: CaseAnalysis) -> pd.DataFrame:
    rows = []
    for solver, s in an.solvers.items():
        if len(s.points):
            pts = s.points.assign(solver=solver, front=s.points.label.isin(s.front))
            rows.append(pts[["solver", "label", "n_dof", "dt", "cpu", "total", "spatial", "front"]])
    if not rows:
        return pd.DataFrame()
    out = pd.concat(rows, ignore_index=True)
    out[["total", "spatial"]] *= 100
    return out.rename(columns={"label": "level", "cpu": "cpu_time_s", "total": "total error, %",
                               "spatial": "same-dt difference, %", "front": "on the front"})


def _truth_tables(an: CaseAnalysis) -> list:
    """The truth per probe and, for a stored truth, its calibration (the columns: Methods)."""
    t = an.truth
    if t is None:
        return []
    blocks = [h("The truth per probe"), table(truth_table([an]).drop(columns=["case", "method", "truth", "source",
                                                                            "cpu_time_s"]))]
    cal = (t.calibration or {}).get("probes")
    if cal:
        rows = pd.DataFrame([{"probe": probe, "uncertainty, %": 100 * c["uncertainty"],
                              "second path's uncertainty, %": 100 * c["second_uncertainty"],
                              "distance, %": 100 * c["distance"], "covered": c["covered"], "sharp": c["sharp"],
                              "widened": c.get("widened", False)}
                             for probe, c in cal.items()])
        blocks += [h(f"Calibration against a second, independent path ({t.calibration['second_path']})"), table(rows)]
    return blocks


def _appendix(an: CaseAnalysis) -> list:
    """The scene's long tables: every run, the orders, the published extrema, the truth per probe,
    the series' ladders."""
    blocks = [h("Every run: total error against the truth, and the same-dt difference"), table(_levels_table(an))]
    if len(an.orders):
        blocks += [h("Observed orders of the headline measure (log-log fit)"), table(an.orders.drop(columns=["case"]))]
    if len(an.published):
        finest = an.published.groupby("solver", sort=False)["level"].transform("last") == an.published["level"]
        blocks += [h(f"Against the published extrema ({an.published.source.iloc[0]}), last level of each solver"),
                   table(an.published[finest].drop(columns=["case", "source"]))]
    blocks += _truth_tables(an)
    if an.runs.carried:
        blocks += [h("Series carried along their ladders (cheapest level first, smfem/studies/ladder.py)"),
                   items([f"{lookup(s).label}: {outcome}" for s, outcome in an.runs.carried.items()])]
    return blocks


def _more_figures(an: CaseAnalysis, figs: dict, out) -> list:
    """The figures after the first: the paper's comparison, the histories, the plastic zones, the field."""
    name = an.case.name
    ref = an.reference.name if an.reference else "none"
    captions = {"spatial": f"{name}: the paper's comparison, at the case's time step: same-dt difference against "
                           f"CPU time (against {ref})",
                "histories": f"{name}: probe histories (truth and each solver's most accurate run)",
                "plastic_zones": f"{name}: SMFEM plastic zones (equivalent plastic strain >= 0.1 %) at the paper's times",
                "field": f"{name}: synthesized 3-D field of SMFEM at the final time"}
    made = [figure(out / figs[key], caption) for key, caption in captions.items() if key in figs]
    blocks = [figures(*made)] if made else []
    if "vtu" in figs:
        blocks.append(link(figs["vtu"], f"{figs['vtu']} (open in ParaView)"))
    if "pvd" in figs:
        blocks.append(link(figs["pvd"], f"{figs['pvd']} (the time series: open in ParaView and play)"))
    return blocks


def scene(ctx, an: CaseAnalysis) -> Section:
    """The section of one scene (``ctx``: :class:`reports.sections.ReportContext`)."""
    name, figs = an.case.name, ctx.figures.get(an.case.name, {})
    head = ctx.tables["headline"]
    rows = head[head.case == name]
    source = an.case.source  # a scene from a file: where it came from, beside its title if it has one
    about = an.case.title if source is None else \
        f"{an.case.title + ': ' if an.case.title != name else ''}a scene from the file {Path(source.path).name}"
    blocks = [p(about)]
    if len(rows):
        blocks.append(p(sentence(name, rows.set_index("solver")), css="verdict"))
    if "work_precision" in figs:
        blocks.append(figure(ctx.out / figs["work_precision"], f"{name}: work-precision diagram (total error)",
                             css="lead"))
    if len(rows):
        blocks.append(table(headline_rows(head, name)))
    unlisted = [f"{s}: {v.status}: {v.message}" for s, v in an.solvers.items() if v.status == NOT_INSTALLED]
    unlisted += an.left_out()  # a procedure that cannot take the scene, beside one that did
    unlisted += [f"{lookup(solver).label}: not run: {why}" for solver, why in an.runs.study.left_out]
    if unlisted:  # not a row of the table: said here
        blocks.append(items(unlisted))
    ran = [solver for solver, s in an.solvers.items() if s.status == OK]
    stresses = family_rows(ctx.tables.get("stresses", pd.DataFrame()), name, ran)
    if len(stresses):
        blocks += [h("Stresses and plastic strains, with their own targets"), table(stresses)]
    if not an.available:
        return Section(name, f"Case {name}", blocks, css="case")
    blocks.append(p(_truth(an)))
    return Section(name, f"Case {name}", blocks + _more_figures(an, figs, ctx.out), css="case",
                   appendix=_appendix(an))
