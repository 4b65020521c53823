"""A picture of the synthesized 3-D field of an SMFEM run (``fields.vtu``), rendered off-screen."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: the largest displacement is drawn as this fraction of the body's bounding-box diagonal
WARP_FRACTION = 0.08


def render_field(vtu: Path, png: Path, title: str) -> Path:
    """Deformed body (displacement magnified) coloured by the plastic strain where the run has
    one, else by the displacement magnitude; cells marked ``solid = 0`` (cut-outs) left out."""
    import pyvista as pv
    from vtkmodules.vtkCommonCore import vtkLogger

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
    plotter = pv.Plotter(off_screen=True, window_size=(900, 640))
    plotter.add_mesh(warped, scalars=scalars, cmap="viridis", show_edges=False,
                     # short labels on a bar kept clear of the window's edges: the last label was cut ("8.99e-")
                     scalar_bar_args={"title": "equivalent plastic strain" if scalars == "peps" else "|displacement|",
                                      "fmt": "%.3g", "position_x": 0.2, "width": 0.6, "n_labels": 4})
    plotter.add_mesh(mesh.extract_feature_edges(), color="gray", line_width=0.5, opacity=0.4)
    plotter.add_text(f"{title}\ndisplacement x {scale:.3g}", font_size=10)
    plotter.view_vector((0.45, -0.9, 1.0))  # from above and aside: rings here are thin in z
    plotter.screenshot(png)
    plotter.close()
    return png
