"""A convergence study from Python: SMFEM on the dome over meshes and time steps, each run's
total error against the stored truth, and the work-precision diagram (error against CPU time).

    python examples/convergence.py [--small]
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import smfem  # noqa: E402

small = "--small" in sys.argv
case = smfem.load("dome")
rows = []
for refine in (1, 2) if small else (1, 2, 4):
    for steps in (1, 2) if small else (1, 2, 4):          # dt, dt/2, dt/4
        run = smfem.run(case, estimate=False, fields=False, refine=refine, dt=case.dt / steps)
        rows.append((refine, steps, run.cpu_time_s, smfem.error(run)))
        print(f"refine {refine}, dt/{steps}: total error {rows[-1][3]:.3%}, CPU {rows[-1][2]:.3f} s")

fig, ax = plt.subplots(figsize=(5, 3.5), layout="constrained")
for steps in sorted({r[1] for r in rows}):
    pts = [r for r in rows if r[1] == steps]
    ax.loglog([p[2] for p in pts], [100 * p[3] for p in pts], "o-", label=f"dt / {steps}, refine 1, 2, ...")
ax.set(xlabel="CPU time, s", ylabel="total error, %", title="dome: SMFEM against the stored truth")
ax.legend()
out = Path("out")
out.mkdir(exist_ok=True)
fig.savefig(out / "convergence.png", dpi=120)
print("work-precision diagram:", out / "convergence.png")
