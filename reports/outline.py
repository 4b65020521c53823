"""The report's outline: every section builder, in the order the document shows them, then the
appendix.

Listed here, not registered by importing a module: a new section is one line in
:data:`OUTLINE` (a ``builder(ctx) -> list[Section]``, :mod:`reports.sections`). A section's long
tables (``Section.appendix``) go to the appendix, so that the sections read as pages, not tables.
"""

from __future__ import annotations

from .blocks import Section, link, p
from .sections import ReportContext, cases, code_verification, estimates, headline, methods, overview, verdict_section
from .stability import stability

OUTLINE = (verdict_section, code_verification, headline, overview, cases, estimates, stability, methods)


def appendix(sections: list[Section]) -> list[Section]:
    """The sections' long tables at the end, each under its section's title; each section gets a
    link to its own."""
    kept = [s for s in sections if s.appendix]
    if not kept:
        return []
    out = [Section("appendix", "Appendix: the tables behind each section", [
        p("Per run and per probe, in the order of the sections; a reason in a cell is a numbered note under its "
          "table. The same tables, every cell whole, are tables/*.csv (tables/README.txt)."),
    ], css="appendix")]
    for s in kept:
        s.blocks.append(link(f"#appendix-{s.id}", f"Its tables per run and per probe: appendix, {s.title}"))
        out.append(Section(f"appendix-{s.id}", f"{s.title}: tables", s.appendix, css="appendix-part"))
    return out


def build_sections(ctx: ReportContext) -> list[Section]:
    sections = [section for builder in OUTLINE for section in builder(ctx)]
    return sections + appendix(sections)
