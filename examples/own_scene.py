"""A scene of one's own: a pipe from a ten-line scene file (pipe.toml), run with SMFEM and with
the independent 2D reference FEM, compared probe by probe, and written for ParaView.

    python examples/own_scene.py [--small]
"""

import sys
from pathlib import Path

import smfem

HERE = Path(__file__).resolve().parent
small = "--small" in sys.argv

case = smfem.load(HERE / "pipe.toml", **({"t_end": 2e-4} if small else {}))
mine = smfem.run(case)                                        # SMFEM, with its error estimate
print(f"{case.name}: {mine.summary['n_dof']} unknowns, {mine.cpu_time_s:.3f} s CPU, "
      f"estimated error {mine.estimate:.2%}")
print(mine.history.iloc[:: max(1, case.n_steps // 8)].to_string(index=False))

ref = smfem.run(case, solver="reference-2d", estimate=False)  # the same scene, full 2D FEM
print(smfem.compare(mine, ref).to_string(index=False))
print(f"reference 2D: {ref.cpu_time_s:.3f} s CPU")
print("written to", mine.write(Path("out") / "pipe-smfem"), "(fields.vtu opens in ParaView)")
