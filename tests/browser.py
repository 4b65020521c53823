"""Headless Chromium for the report tests: a screenshot of a page, and where its verdict lands."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
from PIL import Image


def chromium() -> str | None:
    return next((c for c in ("chromium", "chromium-browser", "google-chrome") if shutil.which(c)), None)


def screenshot(html: Path, shot: Path, size: str) -> None:
    subprocess.run([chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--hide-scrollbars",
                    "--disable-background-networking", f"--user-data-dir={shot.parent / 'profile'}",
                    f"--screenshot={shot}", f"--window-size={size}", html.as_uri()],
                   check=True, timeout=120, capture_output=True)


def verdict_on_first_screen(index: Path, tmp: Path, height: int = 1000) -> tuple[int, int, int]:
    """(top px, bottom px, dark pixels inside) of the verdict section in a 1200 x ``height``
    screenshot of a copy of ``index`` whose verdict is painted magenta; (-1, -1, 0) if it is not
    on that screen."""
    page = index.read_text(encoding="utf-8")
    copy = index.parent / "verdict-marked.html"  # beside the original: the figures' relative paths hold
    copy.write_text(page.replace("</head>", "<style>#verdict { background: #ff00ff !important; }</style></head>", 1),
                    encoding="utf-8")
    try:
        screenshot(copy, tmp / "top.png", f"1200,{height}")
    finally:
        copy.unlink()
    with Image.open(tmp / "top.png") as im:
        rgb = np.asarray(im.convert("RGB")).astype(int)
    magenta = (rgb[..., 0] > 240) & (rgb[..., 1] < 15) & (rgb[..., 2] > 240)
    rows = np.flatnonzero(magenta.any(axis=1))
    if not len(rows):
        return -1, -1, 0
    top, bottom = int(rows[0]), int(rows[-1])
    cols = np.flatnonzero(magenta[top:bottom + 1].any(axis=0))
    box = (slice(top, bottom + 1), slice(cols[0], cols[-1] + 1))
    dark = (rgb[box].sum(axis=-1) < 200) & ~magenta[box]  # glyphs on the magenta
    return top, bottom, int(dark.sum())
