"""A picture of the synthesized 3-D field of an SMFEM run (``fields.vtu``): the body rendered
off-screen by VTK, its title and colour bar drawn by matplotlib, so the picture's text goes
through the same layout check as every other figure (:func:`smfem.runs.figures.save`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: the largest displacement is drawn as this fraction of the body's bounding-box diagonal
WARP_FRACTION = 0.08


def render_field(vtu: Path, png: Path, title: str, length_unit: str) -> Path:
    """Deformed body (displacement magnified) coloured by the plastic strain where the run has
    one, else by the displacement magnitude; cells marked ``solid = 0`` (cut-outs) left out."""
    import pyvista as pv
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from vtkmodules.vtkCommonCore import vtkLogger

    from smfem.runs.figures import save, subplots

    # off-screen rendering needs no X server, but VTK warns about the missing one on every run
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_ERROR)
    mesh = pv.read(vtu)
    if "solid" in mesh.cell_data and not np.all(mesh.cell_data["solid"] > 0):
        # the cut-outs' fictitious material moves far more than the body: out of the picture,
        # the warp scale and the colour range
        mesh = mesh.threshold(0.5, scalars="solid")
    u = mesh.point_data["displacement"]
    umax = float(np.linalg.norm(u, axis=1).max())
    scale = WARP_FRACTION * mesh.length / umax if umax > 0 else 0.0
    mesh.point_data["|u|"] = np.linalg.norm(u, axis=1)
    warped = mesh.warp_by_vector("displacement", factor=scale)
    scalars = "peps" if "peps" in mesh.cell_data else "|u|"
    values = np.asarray(warped.cell_data[scalars] if scalars == "peps" else warped.point_data[scalars], float)
    clim = (float(values.min()), float(values.max()) or 1.0)
    plotter = pv.Plotter(off_screen=True, window_size=(900, 640))
    plotter.add_mesh(warped, scalars=scalars, cmap="viridis", clim=clim, show_edges=False, show_scalar_bar=False)
    # the outline from the surface with coincident points merged: a ring's cells on the axis
    # (each station's own copy of an axis node) would otherwise draw feature edges around it
    outline = mesh.extract_surface(algorithm="dataset_surface").clean().extract_feature_edges()
    plotter.add_mesh(outline, color="gray", line_width=0.5, opacity=0.4)
    plotter.view_vector((0.45, -0.9, 1.0))  # from above and aside: rings here are thin in z
    image = _cropped(plotter.screenshot(return_img=True))
    plotter.close()
    # as tall as the picture needs, up to a page: a rod's picture is narrow then
    fig, ax = subplots(figsize=(7.0, min(7.0 * image.shape[0] / image.shape[1] + 1.3, 8.5)), layout="constrained")
    ax.imshow(image)
    ax.set_axis_off()
    percent = 100.0 if scalars == "peps" else 1.0
    bar = fig.colorbar(ScalarMappable(Normalize(percent * clim[0], percent * clim[1]), "viridis"), ax=ax,
                       orientation="horizontal", shrink=0.7, pad=0.02)
    bar.set_label("equivalent plastic strain, %" if scalars == "peps" else f"|displacement|, {length_unit}", fontsize=9)
    bar.ax.tick_params(labelsize=8)
    ax.set_title(f"{title}: displacement drawn x {scale:.3g}", fontsize=10)
    return save(fig, png)


def _cropped(image: np.ndarray, margin: int = 12) -> np.ndarray:
    """The picture without the empty background around the body."""
    busy = np.flatnonzero((image != image[0, 0]).any(axis=-1).any(axis=1)), \
        np.flatnonzero((image != image[0, 0]).any(axis=-1).any(axis=0))
    if not len(busy[0]):
        return image
    (r0, r1), (c0, c1) = ((max(b[0] - margin, 0), b[-1] + margin + 1) for b in busy)
    return image[r0:r1, c0:c1]
