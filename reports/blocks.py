"""A report section and the blocks it is made of (paragraph, sub-heading, list, table, figure,
a row of figures, link); ``reports/templates/report.html.j2`` lays them out."""

from __future__ import annotations

import base64
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from .compact import footnoted


@dataclass
class Section:
    """``blocks`` in the section's place; ``appendix``: its long tables, which the document
    gathers at its end (:func:`reports.outline.build_sections`)."""

    id: str
    title: str
    blocks: list = field(default_factory=list)
    css: str = ""
    appendix: list = field(default_factory=list)


def p(text, css: str = ""):
    return {"kind": "p", "text": text, "css": css}


def h(text):
    return {"kind": "h", "text": text}


def items(values):
    return {"kind": "list", "entries": list(values)}


def table(df: pd.DataFrame):
    """``df`` as HTML, each reason in a cell once as a numbered note below it
    (:func:`reports.compact.footnoted`)."""
    shown, notes = footnoted(df)
    html = shown.to_html(index=False, na_rep="", border=0, escape=True, float_format=lambda x: f"{x:.4g}")
    return {"kind": "table", "html": html, "notes": notes}


def figure(path: Path, caption: str, css: str = ""):
    data = base64.b64encode(Path(path).read_bytes()).decode()
    return {"kind": "figure", "src": f"data:image/png;base64,{data}", "caption": caption, "css": css}


def figures(*made):
    """Figures side by side, two to a row (the ones that follow a scene's first figure)."""
    return {"kind": "figures", "figures": list(made)}


def link(href: str, text: str):
    return {"kind": "link", "href": href, "text": text}
