"""SMFEM against the independent reference FEM (2D) at converged settings.

Error: relative max-norm over the window, max|a - b| / max|b|, per displacement probe; for
plastic-strain probes the relative difference of the peaks (``smfem.runs.errors.probe_error``).
"""

import numpy as np
import pytest

from cases import get_case
from reference_fem import solve as reference
from smfem.runs.errors import probe_error
from smfem.runs.zones import plastic_area
from smfem.solver import solve as smfem


def error(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


@pytest.mark.parametrize(
    "name,smfem_sets,reference_sets",
    [
        # measured: 1.50 % (SMFEM refine 1: 5.8 %, refine 4: 0.37 %)
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


@pytest.mark.slow
@pytest.mark.parametrize(
    "name,smfem_sets,reference_sets",
    [
        # measured: A 0.40 %, B 1.09 %, C 0.29 %; peaks peps_A +0.08 %, peps_max -6.2 %
        # (at the paper's meshes: B 2.6 %, peps_max -9.7 %: the maximum sits on the outer surface
        # under the patch edge, where each solver samples at its own Gauss points)
        ("thick_cylinder", {"plastic": True, "refine": 2, "harmonics": 40}, {"plastic": True, "refine": 2}),
        # measured: 1.18 % (refine 2 on both sides: 3.9 %)
        ("dome", {"plastic": True, "refine": 4}, {"plastic": True, "refine": 4}),
    ],
)
def test_plastic_displacements_within_five_percent_and_peaks_within_ten(name, smfem_sets, reference_sets):
    s = smfem(get_case(name, smfem_sets), with_fields=False)
    r = reference(get_case(name, reference_sets))
    assert s.converged and r.converged
    for probe, h in s.history.items():
        measure, value = probe_error(probe, s.t, h, r.t, r.history[probe])
        assert abs(value) < (0.10 if measure == "peak difference" else 0.05), (probe, value)


@pytest.mark.slow
@pytest.mark.parametrize(
    "name,smfem_sets,reference_sets",
    [
        # measured: D 1.38 %, E 3.57 %, F 1.53 % (SMFEM refine 4 against reference refine 3:
        # 1.06 / 2.61 / 1.06 %)
        ("notched_cylinder", {"refine": 2, "harmonics": 40}, {"refine": 2}),
        # measured: 1.85 % (120 harmonics; 80: 7.6 %)
        ("notched_strip", {"harmonics": 120}, {}),
    ],
)
def test_plastic_notched_displacements_within_five_percent(name, smfem_sets, reference_sets):
    """Displacements and zones: the notched scenes' plastic-strain probes are not comparable.
    The cylinder's peps_max sits on a re-entrant corner and grows by 61 % and 54 % with each
    refinement of the reference; the strip's notch probes are 28-42 % below the reference,
    from the notch's representation (see the test without the notch below)."""
    s = smfem(get_case(name, smfem_sets), with_fields=False)
    r = reference(get_case(name, reference_sets))
    assert s.converged and r.converged
    for probe, h in s.history.items():
        if not probe.startswith("peps"):
            assert error(h, r.history[probe]) < 0.05, probe
    if name == "notched_cylinder":
        # the zones themselves agree: areas measured -4.3 %, +1.5 %, -5.3 % at 6, 8, 10 ms (256 x3
        # points; on 66 the early zone was 18 % small: SolverOptions.x3_min_points)
        for a, b in zip(s.snapshots, r.snapshots, strict=True):
            assert abs(plastic_area(a) / plastic_area(b) - 1) < 0.10, a.t


def test_plastic_strip_without_the_notch_agrees_to_its_plastic_strains():
    """The control for the notched strip: without the notch SMFEM and the reference agree on
    the plastic strains too, so the notched scene's 28-42 % gap comes from the notch itself:
    absent material along x3, truncated at finitely many harmonics, against the real sharp notch.
    Over the first 60 of its 100 steps (plastic strains to 0.7 %; the reference's 10 CPU s of the
    whole's 19) measured at 40 harmonics: mid_uz 0.14 %, peaks peps_notch +1.5 %, peps_top
    +1.3 % (over the whole window 0.29 %, +2.4 %, -1.2 %)."""
    window = {"notch_depth": 0.0, "t_end": 1.92e-4}
    s = smfem(get_case("notched_strip", {**window, "harmonics": 40}), with_fields=False)
    r = reference(get_case("notched_strip", window))
    assert s.converged and r.converged
    for probe, h in s.history.items():
        measure, value = probe_error(probe, s.t, h, r.t, r.history[probe])
        assert abs(value) < (0.10 if measure == "peak difference" else 0.05), (probe, value)
