"""The reference FEM's plane-strain form of a mesh section (a scene of several bodies round an
axis, ring_in_ring): each body's section swept round the axis into an annulus of 9-node
elements, against the 3D form (one 27-node element along the axis, u_z = 0), which is exactly
plane strain; and the sections that have no such form, refused in one line."""

from dataclasses import replace

import numpy as np
import pytest

from cases import UnsupportedCase, get_case
from cases.geometry import PRISM
from reference_fem.mesh import build_mesh
from reference_fem.model import Model
from smfem.runs.registry import solve

#: 16 elements round the rings, 40 steps: the clearance closes at 2.9 ms
SHORT = dict(theta_elements=16, t_end=4e-3)


def test_plane_strain_rings_equal_the_3d_rings():
    """The same histories to round-off (measured 1e-10 of each probe's largest value, contact_p's
    the worst), the clearance closing at the same step, at a fifth of the CPU."""
    runs = {dim: solve("reference", get_case("ring_in_ring", SHORT | {"dim": dim})) for dim in (2, 3)}
    for res in runs.values():
        assert res.converged and res.info["contact_window"] == pytest.approx([2.9e-3, 4e-3])
    flat, solid = runs[2].history, runs[3].history
    assert set(flat) == set(solid)
    for name in flat:
        a, b = np.asarray(flat[name]), np.asarray(solid[name])
        assert np.abs(a - b).max() <= 1e-8 * np.abs(b).max(), name


@pytest.mark.parametrize("refine", [1, 2])
def test_annulus_keeps_each_bodys_material_and_faces(refine):
    """Each body's elements (8 + 12 through the walls per refinement, 64 round the axis per
    refinement) carry its own material; each named face is a full circle of facets at its
    radius, of its own body's elements only."""
    case = get_case("ring_in_ring", {"refine": refine})
    model = Model(case)
    rmesh = model.rmesh
    n_theta = 64 * refine
    assert rmesh.counts == {"section": 20 * refine, "theta": n_theta, "elements": 20 * refine * n_theta}
    steel, bronze = (np.sum(model.material_index == k) for k in (0, 1))
    assert (steel, bronze) == (8 * refine * n_theta, 12 * refine * n_theta)
    E = np.array([m.E for m in case.materials])[model.material_index]
    centres = model.rmesh.mesh.doflocs[:, model.rmesh.mesh.dofs.element_dofs[-1]]
    assert np.all((E == case.material.E) == (np.hypot(*centres) < 1.0))
    for edge, radius in (("inner.face", 1.0), ("outer.bore", 1.0001), ("inner.bore", 0.8), ("outer.outside", 1.3)):
        facets = model.edge_facets(edge)
        assert len(facets) == n_theta, edge
        corners = rmesh.mesh.p[:, rmesh.mesh.facets[:, facets]]
        assert np.allclose(np.hypot(corners[0], corners[1]), radius, rtol=1e-12), edge


def test_sections_without_a_plane_strain_form_are_refused():
    """A prism's mesh section, and a ring's section that is not the same at every z (the
    flywheel's), in one line each."""
    prism = replace(get_case("ring_in_ring", {"dim": 2}), body=PRISM)
    with pytest.raises(UnsupportedCase, match="a prism's mesh section has no plane-strain 2D form; use dim=3"):
        build_mesh(prism)
    flywheel = get_case("flywheel", {"dim": 2})
    with pytest.raises(UnsupportedCase, match="a stack of rectangles aligned with r and z") as err:
        build_mesh(flywheel)
    assert "\n" not in str(err.value)
