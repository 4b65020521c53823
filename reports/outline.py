"""The report's outline: every section builder, in the order the document shows them.

Listed here, not registered by importing a module: a new section is one line in
:data:`OUTLINE` (a ``builder(ctx) -> list[Section]``, :mod:`reports.sections`).
"""

from __future__ import annotations

from .sections import (ReportContext, Section, cases, code_verification, estimates, headline, methods, overview,
                       verdict_section)
from .stability import stability

OUTLINE = (verdict_section, code_verification, headline, overview, cases, estimates, stability, methods)


def build_sections(ctx: ReportContext) -> list[Section]:
    return [section for builder in OUTLINE for section in builder(ctx)]
