"""The 3D field of a plastic run in pyvista: the notched cylinder's displacement, stress and
plastic strain at the last step, where it yields most, and an off-screen picture.

    python examples/fields_pyvista.py [--small]
"""

import sys
from pathlib import Path

import numpy as np
import pyvista

import smfem

small = "--small" in sys.argv
run = smfem.run("notched_cylinder", estimate=False, **({"harmonics": 20} if small else {}))
grid = run.to_pyvista()                       # an UnstructuredGrid: point and cell arrays
print(grid)
print("arrays:", grid.array_names)
u = np.linalg.norm(grid.point_data["displacement"], axis=1)
print(f"largest displacement {u.max():.3e} m; largest equivalent plastic strain {grid.cell_data['peps'].max():.3%}")
worst = grid.extract_cells(int(np.argmax(grid.cell_data["peps"])))
print(f"it is at {np.round(worst.center, 3)} m")

pyvista.OFF_SCREEN = True
out = Path("out")
out.mkdir(exist_ok=True)
plotter = pyvista.Plotter(off_screen=True, window_size=(640, 480))
plotter.add_mesh(grid.cell_data_to_point_data(), scalars="peps", cmap="viridis")
plotter.screenshot(out / "notched_cylinder_peps.png")
print("picture:", out / "notched_cylinder_peps.png")
