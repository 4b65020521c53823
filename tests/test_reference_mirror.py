"""The 3D reference's mirror half (``--set mirror=true``): a ring whose loads and material are
symmetric about theta = 0 meshed over 0 <= theta <= pi with u_theta = 0 on the mirror planes,
what a 3D analyst would mesh. Half the unknowns, the whole's histories."""

from __future__ import annotations

import dataclasses
import math
import shutil

import numpy as np
import pytest
from test_mesh_sections_reference import relative, ring_case

from cases import UnsupportedCase, get_case
from cases.geometry import Probe
from smfem.runs.registry import solve


def test_the_mirror_half_of_the_layered_cylinder_gives_the_whole_ones_histories_with_half_the_unknowns():
    base = {"dim": 3, "t_end": 4e-4}
    whole = solve("reference-3d", get_case("layered_cylinder", base))
    half = solve("reference-3d", get_case("layered_cylinder", {**base, "mirror": True}))
    assert half.n_dof == whole.n_dof // 2
    for name in ("A_ur", "B_ut", "C_ur", "I_ur"):
        assert relative(half.history[name], whole.history[name]) < 1e-10, name


def test_the_mirror_half_of_a_mesh_section_ring_agrees_with_the_whole(tmp_path):
    """The gmsh L-section with a patch over |theta| <= 45 deg, 16 elements round the whole (so
    that the half's mesh is the whole's mirror image: 2 + 6 elements either side)."""
    case = ring_case(tmp_path, 3, ((-math.pi / 4, math.pi / 4),))
    case = dataclasses.replace(case, axisymmetric=False, params={**case.params, "theta_elements": 16, "t_end": 0.2})
    whole = solve("reference-3d", case)
    half = solve("reference-3d", dataclasses.replace(case, params={**case.params, "mirror": True}))
    assert half.n_dof < 0.6 * whole.n_dof
    assert relative(half.history["p"], whole.history["p"]) < 1e-10


def test_what_has_no_mirror_half_is_refused_in_one_line():
    cylinder = get_case("thick_cylinder", {"dim": 3, "mirror": True})
    behind = Probe("behind", "point", "u", (1,), point=(1.0, 0.0, 1.5 * math.pi))
    cases = {
        "dim=3 on a ring": get_case("thick_cylinder", {"dim": 2, "mirror": True}),
        "symmetric about": dataclasses.replace(cylinder, symmetric=False),
        "outside the mirror half": dataclasses.replace(cylinder, probes=cylinder.probes + (behind,)),
        "reaches the axis": get_case("dome", {"dim": 3, "mirror": True}),
    }
    for words, case in cases.items():
        with pytest.raises(UnsupportedCase, match=words) as err:
            solve("reference", case)
        assert "\n" not in str(err.value)
    assert np.isfinite(solve("reference-3d", dataclasses.replace(cylinder, params={**cylinder.params, "t_end": 4e-5}))
                       .history["A_ur"]).all()


@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed")
def test_calculix_takes_the_mirror_half_from_the_references_supports():
    """The deck's *BOUNDARY lines are the reference's fixed dofs, the mirror planes' too: the half
    gives the whole's histories (to ccx's printed digits) with half the elements."""
    base = {"dim": 3, "t_end": 2e-4}
    whole = solve("calculix", get_case("thick_cylinder", base))
    half = solve("calculix", get_case("thick_cylinder", {**base, "mirror": True}))
    assert half.info["n_elements"] * 2 == whole.info["n_elements"]
    for name in ("A_ur", "B_ut", "C_ur"):
        assert relative(half.history[name], whole.history[name]) < 1e-5, name
