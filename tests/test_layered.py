"""Several materials in one section (SMFEM): the layered cylinder's regions."""

import dataclasses

import numpy as np

from cases import get_case
from cases.geometry import Region
from smfem.runs.registry import solve


def test_a_region_of_the_bodys_own_material_changes_nothing():
    case = get_case("thick_cylinder", {"nu": 0.3, "t_end": 4e-4})
    dz = case.section.t.breaks[-1]
    same = dataclasses.replace(case, regions=(Region("outer", case.material, (1.4, 2.0), (0.0, dz)),))
    a, b = solve("smfem", case).history, solve("smfem", same).history
    for name in a:
        assert np.allclose(b[name], a[name], rtol=1e-12, atol=1e-12 * np.abs(a[name]).max()), name


def test_the_layers_materials_both_act():
    """A softer outer layer moves the loaded surface more than all steel, less than all aluminium."""
    params = {"t_end": 4e-4}
    layered = get_case("layered_cylinder", params)
    outer = layered.regions[0].material
    steel = dataclasses.replace(layered, regions=())
    aluminium = dataclasses.replace(layered, material=outer, regions=())
    peak = {k: np.abs(solve("smfem", c).history["A_ur"]).max() for k, c in
            (("layered", layered), ("steel", steel), ("aluminium", aluminium))}
    assert peak["steel"] < peak["layered"] < peak["aluminium"]


def test_the_plastic_variant_yields_both_layers():
    case = get_case("layered_cylinder", {"plastic": True, "t_end": 2e-3})
    result = solve("smfem", case, fields=True)
    assert result.converged
    mesh = result.mesh
    peps = mesh.cell_data["peps"][0]
    centres = mesh.points[mesh.cells[0].data].mean(axis=1)
    r = np.hypot(centres[:, 0], centres[:, 1])
    assert peps[r < 1.4].max() > 1e-4 and peps[r > 1.4].max() > 1e-4
    region = mesh.cell_data["region"][0]  # for ParaView: each cell's material
    assert np.all(region == (r > 1.4))
