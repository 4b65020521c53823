"""The report as one self-contained HTML file (jinja2) and the same content as PDF (weasyprint)."""

from __future__ import annotations

import logging
from pathlib import Path

import jinja2


def render_html(sections, title: str, subtitle: str) -> str:
    env = jinja2.Environment(loader=jinja2.PackageLoader("reports", "templates"),
                             autoescape=jinja2.select_autoescape(["html", "j2"]))
    return env.get_template("report.html.j2").render(sections=sections, title=title, subtitle=subtitle)


def write_pdf(html: str, path: Path, base: Path) -> Path:
    """Print ``html`` to ``path``; relative links resolve against ``base``."""
    import weasyprint

    logging.getLogger("fontTools").setLevel(logging.WARNING)  # font subsetting chatter
    weasyprint.HTML(string=html, base_url=str(base)).write_pdf(path)
    return path
