"""A run's files (docs/contract.md): history.csv, summary.json, fields.vtu, fields.pvd, plastic zones."""

from __future__ import annotations

import json
import math
from pathlib import Path

import meshio
import numpy as np
import pandas as pd

from cases.result import RunResult
from smfem.version import __version__

from . import validity


def summary(case, solver: str, result, wall_time_s: float, checked: dict | None = None) -> dict:
    """The summary.json content of a run (``checked``: its validity, when already made)."""
    its = np.asarray(result.iterations, float)
    return {
        "case": case.name,
        "solver": solver,
        "params": {k: v for k, v in case.params.items()},
        "n_dof": int(result.n_dof),
        "n_steps": len(result.iterations),
        "wall_time_s": wall_time_s,
        "cpu_time_s": result.cpu_time_s,
        "iterations": {"mean": float(its.mean()) if its.size else 0.0, "max": int(its.max()) if its.size else 0,
                       "per_step": [int(i) for i in result.iterations]},
        "converged": bool(result.converged),
        "message": result.message,
        "harmonics_used": result.info.get("harmonics_used"),
        "validity": checked if checked is not None else validity.check(case, result),
        "info": {k: v for k, v in result.info.items() if k != "harmonics_used"},
        "version": __version__,
    }


def jsonable(x):
    """``x`` with numpy scalars as Python numbers and non-finite floats as strings."""
    if isinstance(x, float) and not math.isfinite(x):
        return str(x)
    if isinstance(x, dict):
        return {k: jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.generic):
        return x.item()
    return x


def write_series(out: Path, frames) -> None:
    """``fields.pvd``, the ParaView collection of ``fields_NNNNN.vtu``, one per ``(t, mesh)``;
    the frames' fields in single precision (half the files; plenty to look at)."""
    entries = []
    for k, (t, mesh) in enumerate(frames):
        name = f"fields_{k:05d}.vtu"
        single = meshio.Mesh(mesh.points, mesh.cells,
                             point_data={key: np.asarray(v, np.float32) for key, v in mesh.point_data.items()},
                             cell_data={key: [np.asarray(v, np.float32) for v in vs] for key, vs in mesh.cell_data.items()})
        single.write(out / name)
        entries.append(f'    <DataSet timestep="{t:.12g}" part="0" file="{name}"/>')
    (out / "fields.pvd").write_text('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
                                    "  <Collection>\n" + "\n".join(entries) + "\n  </Collection>\n</VTKFile>\n")


def write_run(out: Path, case, solver: str, result, wall_time_s: float, zone_figure: bool = True,
              extra: dict | None = None) -> dict:
    """Write history.csv (one row per time of ``result.t``, t = 0 included), summary.json, fields.vtu,
    with a time series fields.pvd and its fields_NNNNN.vtu, and for plastic runs
    plastic_zones.npz with (``zone_figure``) its picture plastic_zones.png; ``extra``: more
    summary entries (``error_estimate``; ``validity`` when already checked). Returns the summary."""
    out.mkdir(parents=True, exist_ok=True)
    n = len(result.t)  # a run that stopped early has its converged steps only; a modal run no steps
    table = pd.DataFrame({"t": result.t[:n], **{k: v[:n] for k, v in result.history.items()}})
    table.to_csv(out / "history.csv", index=False, float_format="%.10g")
    extra = dict(extra or {})
    written = {**summary(case, solver, result, wall_time_s, extra.pop("validity", None)), **extra}
    (out / "summary.json").write_text(json.dumps(jsonable(written), indent=2))
    if result.mesh is not None:
        result.mesh.write(out / "fields.vtu")
    if getattr(result, "frames", None):
        write_series(out, result.frames)
    if getattr(result, "snapshots", None):
        from .figures import plastic_zones
        from .zones import save

        save(result.snapshots, out / "plastic_zones.npz")
        if zone_figure:
            plastic_zones({solver: result.snapshots}, out / "plastic_zones.png", f"{case.name}: plastic zones", case)
    return written


def add_to_summary(out: Path, extra: dict) -> dict:
    """Add ``extra`` entries to the summary.json of a run written already (its error estimate,
    made once the run is safe on disk); returns the summary."""
    path = Path(out) / "summary.json"
    written = {**json.loads(path.read_text()), **extra}
    path.write_text(json.dumps(jsonable(written), indent=2))
    return written


def read_run(path: Path, fields: bool = True) -> tuple[RunResult, dict]:
    """The :class:`RunResult` that :func:`write_run` took, read back from its directory, and the
    summary.json beside it: the histories (to the 10 significant digits history.csv keeps), the
    per-step iterations, the facts, the last field (fields.vtu), the time series (fields.pvd) and
    the plastic zones (plastic_zones.npz); without ``fields`` the meshes stay on disk (a study
    reads hundreds of runs). ``info`` is as JSON holds it (a non-finite number as its string)."""
    path = Path(path)
    table = pd.read_csv(path / "history.csv")
    written = json.loads((path / "summary.json").read_text())
    info = dict(written.get("info") or {})
    if written.get("harmonics_used") is not None:
        info["harmonics_used"] = written["harmonics_used"]
    frames = []
    if fields and (path / "fields.pvd").exists():
        import xml.etree.ElementTree as ET

        for entry in ET.parse(path / "fields.pvd").iter("DataSet"):
            frames.append((float(entry.get("timestep")), meshio.read(path / entry.get("file"))))
    snapshots = []
    if (path / "plastic_zones.npz").exists():
        from .zones import load

        snapshots = load(path / "plastic_zones.npz")
    result = RunResult(
        t=table["t"].to_numpy(), history={c: table[c].to_numpy() for c in table.columns if c != "t"},
        n_dof=int(written["n_dof"]), iterations=list((written.get("iterations") or {}).get("per_step", [])),
        converged=bool(written["converged"]), message=written.get("message", ""),
        cpu_time_s=float(written["cpu_time_s"]),
        mesh=meshio.read(path / "fields.vtu") if fields and (path / "fields.vtu").exists() else None,
        info=info, snapshots=snapshots, frames=frames)
    return result, written
