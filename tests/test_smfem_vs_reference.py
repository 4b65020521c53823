"""SMFEM against the independent reference FEM (2D) at converged settings.

Error: relative max-norm over the window, max|a - b| / max|b|, per displacement probe; for
plastic-strain probes the relative difference of the peaks (``smfem.compare.probe_error``).
"""

import numpy as np
import pytest

from cases import get_case
from reference_fem import solve as reference
from smfem.compare import probe_error
from smfem.solver import solve as smfem


def error(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


@pytest.mark.parametrize(
    "name,smfem_sets,reference_sets",
    [
        # measured: 1.77 % (SMFEM refine 1: 5.9 %, refine 4: 0.51 %)
        ("dome", {"refine": 2}, {"refine": 4}),
        # measured: A 0.06 %, B 0.50 %, C 0.04 %; B_ut on the patch edge needs 80 harmonics (2.1 % at 20)
        ("thick_cylinder", {"refine": 4, "harmonics": 80}, {"refine": 3}),
        # measured: 1.78 %; the 10 mm notch needs many harmonics (3.4 % static at 80)
        ("notched_strip", {"plastic": False, "harmonics": 120}, {"plastic": False, "refine": 2}),
        # measured: D 1.14 %, E 1.49 %, F 1.14 % (SMFEM at the paper's 14 x 20: 2.6-3.3 %)
        ("notched_cylinder", {"plastic": False, "refine": 2, "harmonics": 40}, {"plastic": False, "refine": 2}),
    ],
)
def test_elastic_displacement_probes_within_two_percent(name, smfem_sets, reference_sets):
    s = smfem(get_case(name, smfem_sets), with_fields=False)
    r = reference(get_case(name, reference_sets))
    for probe, h in s.history.items():
        assert error(h, r.history[probe]) < 0.02, probe
