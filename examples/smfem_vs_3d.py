"""SMFEM against the full 3D reference FEM on the thick cylinder, both measured against the
scene's stored truth (converged histories with a stated uncertainty): total error and CPU time.

    python examples/smfem_vs_3d.py [--small]
"""

import sys

import smfem

small = "--small" in sys.argv
case = smfem.load("thick_cylinder")
truth = smfem.truth(case)
print(f"truth: {truth.name}, uncertainty up to {100 * truth.uncertainty_of(case.probe_names):.2g} %")

runs = {
    "SMFEM, 9-node element, 80 harmonics": smfem.run(case, estimate=False, element="quad9", time_scheme="gauss",
                                                     harmonics=80, dt=1e-5),
    "reference FEM 3D, refine 1": smfem.run(case, solver="reference-3d", estimate=False, fields=False,
                                            **({"dt": 4e-5} if small else {"dt": 1e-5})),
}
for name, run in runs.items():
    print(f"{name:38s} total error {smfem.error(run):7.2%}   CPU {run.cpu_time_s:7.3f} s   "
          f"{run.summary['n_dof']} unknowns")
# at equal total error (1 %) the 3D reference needs refine 3 at dt / 16: docs/full-report has it
