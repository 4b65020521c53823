"""Stored truths (``smfem/truths/CASE``): their key, writing and reading.

A stored truth is the ``--full`` truth of a scene at its own parameters, made once by
``smfem truth CASE --full`` and kept with the code. Its key is a hash of what decides it: the
case's definition (geometry, material, loads, supports, probes, parameters, the comparison
window and the probes without a converged truth), the truth's plan (method, ladders, options)
and :data:`METHOD_VERSION`, raised whenever the truth's numerics change what they give.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import json
from pathlib import Path

import pandas as pd

from smfem.truths import ROOT

from .truth import Truth

#: raise when the truth engines change their results (a stored truth then no longer matches)
METHOD_VERSION = 1
#: the case's references that decide a truth
TRUTH_REFERENCES = ("comparison_window_s", "singular_probes")


def case_definition(case) -> dict:
    """The parts of ``case`` a truth depends on, as plain data."""
    mesh = getattr(case.section, "kind", "") == "mesh"  # its arrays by digest: numpy's text of them is cut short
    shallow = copy.copy(case)  # not dataclasses.replace: a case without its section is no valid case
    object.__setattr__(shallow, "source", None)
    if mesh:
        object.__setattr__(shallow, "section", None)
    d = dataclasses.asdict(shallow)
    if mesh:
        d["section"] = {"mesh": case.section.digest()}
    for name in ("title", "provenance", "source", "units", "references"):
        d.pop(name, None)
    d["references"] = {k: case.references[k] for k in TRUTH_REFERENCES if k in case.references}
    for name in ("forces", "variation", "exact", "regions", "contacts"):  # features a scene may leave out: absent, as before they existed
        if not d.get(name):
            d.pop(name, None)
    for item in [*d["probes"], *d["initial_velocity"]]:  # the whole body: as before regions could be named
        if item.get("region") is None:
            item.pop("region", None)
    for load in [*d["loads"], *d.get("forces", ())]:  # a step held in place: as before loads had a history
        if load.get("amplitude") is None:
            load.pop("amplitude", None)
        if not load.get("speed"):
            load.pop("speed", None)
    return d


def key_of(case, plan) -> str:
    """sha256 (16 hex digits) of the case's definition, the plan and the method version."""
    text = json.dumps({"case": case_definition(case), "plan": plan.describe(), "version": METHOD_VERSION},
                      sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def directory(name: str, root: Path | None = None) -> Path:
    return Path(root or ROOT) / name


def read(path: Path) -> Truth:
    """The truth stored in directory ``path``."""
    summary = _numbers(json.loads((path / "summary.json").read_text()))
    history = pd.read_csv(path / "history.csv")
    return Truth(summary["case"], summary["method"], summary["name"], history["t"].to_numpy(),
                 {c: history[c].to_numpy() for c in history.columns if c != "t"},
                 summary["uncertainty"], summary["parts"], summary["notes"], summary["levels"],
                 summary["cpu_time_s"], summary.get("comparison_window_s", 0.0), params=summary.get("params", {}),
                 key=summary.get("key", ""), calibration=summary.get("calibration", {}),
                 source=f"stored in {_shown(path)} (key {summary.get('key', '')})")


def _shown(path: Path) -> str:
    """``smfem/truths/CASE`` for a stored truth of the package (the reader's repository, not this
    machine's path); other directories as given."""
    try:
        return str(Path(ROOT.name) / Path(path).resolve().relative_to(ROOT))
    except ValueError:
        return str(path)


def _numbers(x):
    """``x`` with the non-finite floats that JSON holds as strings (``'nan'``) as floats again."""
    if isinstance(x, str) and x in ("nan", "inf", "-inf"):
        return float(x)
    if isinstance(x, dict):
        return {k: _numbers(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_numbers(v) for v in x]
    return x


def find(name: str, case, plan, root: Path | None = None) -> tuple[Truth | None, str]:
    """The stored truth of scene ``name`` if its key matches ``case`` and ``plan``, and why not
    otherwise (an empty reason when it does)."""
    path = directory(name, root)
    if not (path / "summary.json").exists():
        return None, f"no stored truth in {path}"
    stored = json.loads((path / "summary.json").read_text()).get("key")
    if stored != key_of(case, plan):
        return None, (f"the stored truth in {path} was made for another case definition or truth method "
                      "(its key does not match)")
    return read(path), ""


#: a scene's measured work-precision points, kept beside its stored truth
FRONT = "front.csv"


def stored_key(name: str, root: Path | None = None) -> str:
    """The key of scene ``name``'s stored truth ('' when there is none)."""
    path = directory(name, root) / "summary.json"
    return json.loads(path.read_text()).get("key", "") if path.exists() else ""


def write_fronts(fronts: pd.DataFrame, root: Path | None = None) -> list[str]:
    """Keep each scene's rows of a report's ``fronts.csv`` (:func:`reports.tables.fronts_table`)
    that were measured against its stored truth, as ``smfem/truths/CASE/front.csv``; returns the
    scenes written."""
    written = []
    for name, rows in fronts.groupby("case", sort=False) if len(fronts) else ():
        key = stored_key(name, root)
        rows = rows[rows.truth_key == key] if key else rows.iloc[:0]
        if len(rows):
            rows.to_csv(directory(name, root) / FRONT, index=False, float_format="%.6g")
            written.append(name)
    return written


def read_front(name: str, root: Path | None = None) -> pd.DataFrame | None:
    """Scene ``name``'s stored work-precision points while the truth they were measured against
    is still the stored one; None otherwise."""
    path = directory(name, root) / FRONT
    if not path.exists():
        return None
    front = pd.read_csv(path)
    key = stored_key(name, root)
    return front if key and len(front) and (front.truth_key == key).all() else None
