"""Whether a run stays inside the model both solvers share: small strains, small rotations.

Both solvers are small-strain, small-rotation models: past a few per cent of strain, or a
displacement that is a sizeable part of the body's thinnest dimension, their numbers no longer
describe the physical body, however well converged. A run checks itself against three limits
(:data:`LIMITS`) and says so in ``summary.json`` (``validity``), in one warning line, and in the
report; its error estimate then claims nothing.

The figures, from what every run has:
- displacement: the largest displacement probe over the whole history, and the largest nodal
  displacement of the final field (and of the time series' frames), against the smallest
  refinable extent of the cross-section (a shell's thickness, a wall's, a rod's radius);
- strain: the largest equivalent plastic strain probe over the history, and the largest
  principal strain of the final field (each cell's displacement gradient fitted over its nodes);
- rotation: the largest rotation angle of the field's cells, |skew(grad u)|.
A run without a field (``--no-fields``) is judged on its probes alone, and says so.
"""

from __future__ import annotations

import math

import numpy as np

#: past these the small-strain, small-rotation model says nothing about the physical body
LIMITS = {"strain": 0.05, "rotation": 0.10, "displacement_ratio": 0.10}
#: what each limit means, for the warning line and the documents
MEANING = {"strain": "largest strain (plastic or total)", "rotation": "largest rotation, rad",
           "displacement_ratio": "largest displacement / thinnest dimension"}


def smallest_dimension(case) -> float:
    """The smallest extent of the cross-section along a refinable axis (a polar section: its
    thickness; a one-element plane-strain slice does not count; a mesh section: its bounding
    box's smaller side)."""
    sec = case.section
    if sec.kind == "mesh":
        return sec.smallest_dimension
    spans = []
    if sec.s.refinable or sec.kind == "polar":
        spans.append(abs(sec.s.span[1] - sec.s.span[0]))
    if sec.t.refinable and sec.kind == "rect":
        spans.append(abs(sec.t.span[1] - sec.t.span[0]))
    return min(spans) if spans else abs(sec.s.span[1] - sec.s.span[0])


def field_gradients(mesh) -> np.ndarray:
    """(n_cells, d, d) displacement gradient per cell of a meshio field, fitted (least squares,
    linear in x) over the cell's nodes; d = 3 for a solid, 2 for a section."""
    pts = np.asarray(mesh.points, float)
    u = np.asarray(mesh.point_data["displacement"], float)
    d = 3 if np.ptp(pts[:, 2]) > 0 else 2 if pts.shape[1] >= 2 else 1
    out = []
    for block in mesh.cells:
        x, v = pts[block.data][..., :d], u[block.data][..., :d]  # (nc, nn, d)
        xc = x - x.mean(axis=1, keepdims=True)
        vc = v - v.mean(axis=1, keepdims=True)
        a = np.einsum("cni,cnj->cij", xc, xc)  # normal equations of v = v0 + G (x - x0)
        b = np.einsum("cni,cnj->cij", xc, vc)
        ok = np.linalg.matrix_rank(a) == d
        g = np.zeros_like(a)
        g[ok] = np.swapaxes(np.linalg.solve(a[ok], b[ok]), 1, 2)  # G[i, j] = dv_i / dx_j
        out.append(g)
    return np.concatenate(out) if out else np.zeros((0, d, d))


def _field_figures(mesh) -> tuple[float, float, float]:
    """(largest |principal strain|, largest rotation, largest |u|) of a field's solid cells."""
    g = field_gradients(mesh)
    if "solid" in mesh.cell_data:  # SMFEM's fictitious cut-out material is not the body
        g = g[np.concatenate(mesh.cell_data["solid"]).astype(bool)]
    if not len(g):
        return 0.0, 0.0, 0.0
    eps = 0.5 * (g + np.swapaxes(g, 1, 2))
    w = 0.5 * (g - np.swapaxes(g, 1, 2))
    strain = float(np.abs(np.linalg.eigvalsh(eps)).max())
    rotation = float(np.sqrt(0.5 * (w ** 2).sum(axis=(1, 2))).max())  # the angle of a small rotation
    disp = float(np.linalg.norm(np.asarray(mesh.point_data["displacement"], float), axis=1).max())
    return strain, rotation, disp


def check(case, result) -> dict:
    """``validity`` of a run: the figures, the limits, ``valid`` and ``exceeded`` (limit names),
    and what the figures come from."""
    fields = {p.name: p.field for p in case.probes}
    peak = lambda kind: max([float(np.nanmax(np.abs(v))) for name, v in result.history.items()
                             if fields.get(name) == kind and len(v) and np.isfinite(v).any()] + [0.0])
    strain, disp, rotation = peak("peps"), peak("u"), 0.0
    meshes = [m for m in [getattr(result, "mesh", None), *(m for _, m in getattr(result, "frames", None) or ())]
              if m is not None and "displacement" in m.point_data]
    for mesh in meshes:
        s, r, u = _field_figures(mesh)
        strain, rotation, disp = max(strain, s), max(rotation, r), max(disp, u)
    thin = smallest_dimension(case)
    figures = {"strain": strain, "rotation": rotation, "displacement_ratio": disp / thin if thin > 0 else math.inf}
    exceeded = [k for k, v in figures.items() if not v <= LIMITS[k]]
    return {**figures, "largest_displacement": disp, "smallest_dimension": thin, "limits": dict(LIMITS),
            "valid": not exceeded, "exceeded": exceeded,
            "from": "probes and fields" if meshes else "probes only (no field written)"}


def warning_line(case, validity: dict) -> str | None:
    """One line naming each figure past its limit, or None for a valid run."""
    if validity["valid"]:
        return None
    parts = [f"{MEANING[k]} {validity[k]:.3g} > {LIMITS[k]:g}" for k in validity["exceeded"]]
    return (f"smfem: {case.name}: outside the small-strain model ({'; '.join(parts)}): the results do not "
            "describe the physical body, and no error estimate is claimed")
