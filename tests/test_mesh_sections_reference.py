"""The reference solvers on mesh sections (reference_fem/swept.py): the section's own 9-node
elements in 2D and in the harmonic model, swept into 27-node hexahedra in 3D; named edges found
by the section's segments."""

import dataclasses
import math

import numpy as np
import pytest

from cases import UnsupportedCase, get_case
from cases import verification_mesh as vm
from cases.case import Case
from cases.geometry import RING, Pressure, Probe, Support
from cases.material import Material
from cases.flywheel import MESH
from cases.msh_section import read_msh
from smfem.runs.registry import solve

SECTIONS = MESH.parent  # cases/sections: the kept gmsh meshes


def relative(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


def test_the_flywheel_axisymmetric_agrees_between_smfem_quad9_and_the_reference_2d():
    """Same 9-node section elements, same dt: only the two codes' spatial forms differ."""
    case = get_case("flywheel", {"patch_deg": 180.0, "t_end": 5e-4, "element": "quad9"})
    smfem, reference = solve("smfem", case), solve("reference-2d", case)
    assert relative(smfem.history["rim_uz_0"], reference.history["rim_uz_0"]) < 1e-4


def test_the_rod_on_its_gmsh_section_agrees_with_the_mapped_rod_in_the_reference():
    mapped = get_case("rod_impact", {"t_end": 2e-4})
    mesh = dataclasses.replace(mapped, section=read_msh(SECTIONS / "rod_impact.msh"))
    a, b = solve("reference-2d", mapped).history, solve("reference-2d", mesh).history
    for name in ("contact_p", "end_uz", "rod_vz"):
        assert relative(b[name], a[name]) < 1e-3, name


def ring_case(tmp_path, dim, x3_intervals=((0.0, 2 * math.pi),)):
    section = read_msh(vm.write(tmp_path / "L.msh", RING), RING)
    point = (*vm.to_x(RING, np.array([vm.PROBE_ST]))[0], 0.0)
    return Case(name="L_ring", title="L", body=RING, section=section, material=Material(1.0, 0.3, 1.0),
                loads=(Pressure(1.0, "notch", x3_intervals),), supports=(Support("outer", (1, 2, 3)),),
                probes=(Probe("p", "point", "u", (1,), point=point),),
                params=dict(dt=0.02, t_end=0.4, refine=1, harmonics=4, tol=1e-5, dim=dim),
                axisymmetric=len(x3_intervals) == 1 and x3_intervals[0] == (0.0, 2 * math.pi))


def test_the_swept_3d_mesh_of_an_axisymmetric_scene_agrees_with_the_2d_section(tmp_path):
    """An L-shaped section of two regions, loaded all round: the 3D model swept from it (64
    elements round) against the axisymmetric 2D model on the same section elements."""
    two, three = solve("reference-2d", ring_case(tmp_path, 2)), solve("reference-3d", ring_case(tmp_path, 3))
    assert relative(three.history["p"], two.history["p"]) < 1e-3


def test_theta_elements_sets_the_3d_circumference_of_a_mesh_section_and_of_a_block(tmp_path):
    """A section of thousands of elements fits in memory in 3D only with fewer elements round
    than 64 (the flywheel: 1.3 million unknowns at 64); break points still add their nodes."""
    from reference_fem.mesh import build_mesh

    ring = ring_case(tmp_path, 3)
    counted = lambda case, **p: build_mesh(dataclasses.replace(case, params={**case.params, **p})).counts  # noqa: E731
    assert counted(ring)["x3"] == 64 and counted(ring, theta_elements=8)["x3"] == 8
    patch = ring_case(tmp_path, 3, ((-0.3, 0.3),))  # 0.3 rad: no node of 8 equal elements
    assert 8 < counted(patch, theta_elements=8)["x3"] <= 10
    cylinder = get_case("thick_cylinder", {"dim": 3, "theta_elements": 16})
    assert build_mesh(cylinder).counts["theta"] == 16


def test_what_the_reference_cannot_mesh_is_refused_in_one_line(tmp_path):
    with pytest.raises(UnsupportedCase, match="cannot be coarsened"):
        solve("reference-2d", dataclasses.replace(ring_case(tmp_path, 2), params={**ring_case(tmp_path, 2).params,
                                                                                 "coarsen": 2}))


@pytest.mark.parametrize("name", ["dome", "rod_impact"])
def test_the_unstructured_examples_are_the_builtin_scenes_on_a_gmsh_section(name):
    from pathlib import Path

    examples = Path(__file__).resolve().parents[1] / "examples"
    builtin, mesh = get_case(name), get_case(examples / f"{name}_unstructured.toml")
    assert mesh.section.kind == "mesh" and mesh.name == f"{name}_unstructured"
    for field in ("body", "material", "loads", "supports", "probes", "params", "wall", "axisymmetric"):
        assert getattr(mesh, field) == getattr(builtin, field), field
    short = {"t_end": 20 * builtin.dt}
    a = solve("smfem", get_case(name, short)).history
    b = solve("smfem", get_case(examples / f"{name}_unstructured.toml", short)).history
    probe = builtin.probe_names[-1]
    assert relative(b[probe], a[probe]) < 0.05  # the same body, another mesh
