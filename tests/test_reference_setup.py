"""The reference FEM's set-up, made cheaper, gives the numbers it gave: the initial acceleration
by CG on the mass, the strain operator made only where stresses are read (a probe's rows from
its element alone), a face's row of K from the face's elements and K from node pairs, the mass
element by element and its copies per component, a probe at a node read at the node, the
mapping's inverse and shape functions kept for the points last asked for, the vector element's
scalar function kept for its components, and the 3D moving load's histories
(benchmarks/competitor_profile.py measures the set-up's share of each run)."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest
import scipy.sparse as sp
from skfem import BilinearForm, ElementVector, asm
from skfem.helpers import dot
from skfem.mapping import MappingIsoparametric

from cases import get_case
from reference_fem import forms, ties
from reference_fem.linalg import factorize, solve_mass
from reference_fem.mass import component_copies, consistent_mass
from reference_fem.mesh import INVF_TOL
from reference_fem.model import AXISYMMETRIC, INTORDER, Model
from reference_fem.probes import value_probes

#: small models of each representation: axisymmetric, 3D solid, B-bar, two materials (D per element)
MODELS = {"dome 2D": ("dome", {}, False), "thick cylinder 3D": ("thick_cylinder", {"dim": 3}, False),
          "notched cylinder B-bar": ("notched_cylinder", {}, True),
          "layered cylinder 3D": ("layered_cylinder", {"dim": 3}, False)}


@pytest.fixture(scope="module", params=list(MODELS))
def model(request):
    name, sets, bbar = MODELS[request.param]
    return Model(get_case(name, sets), bbar=bbar)


@BilinearForm
def _vector_mass(u, v, w):
    return w.rho * dot(u, v) * w.weight


def test_the_mass_solved_by_cg_equals_its_factors(model):
    M, b = model.M[model.free][:, model.free], model.Q[model.free]
    expected = factorize(M).solve(b)
    assert np.abs(solve_mass(M, b) - expected).max() <= 1e-13 * np.abs(expected).max()


def test_the_mass_element_by_element_equals_the_vector_form(model):
    basis = model.basis
    radius = np.asarray(basis.global_coordinates())[0] if model.rep == AXISYMMETRIC else np.ones(basis.dx.shape)
    expected = asm(_vector_mass, basis, rho=model.case.material.rho, weight=radius)
    M = consistent_mass(basis, model.case.material.rho, model.rep == AXISYMMETRIC)
    assert abs(M - expected).max() <= 1e-14 * abs(expected).max()


def test_component_copies_are_the_kronecker_product():
    M = sp.random(40, 40, density=0.1, random_state=2, format="lil")
    M[5, :] = 0.0  # an empty row
    M = M.tocsr()
    for dim in (2, 3):
        copies, expected = component_copies(M, dim), sp.kron(M, sp.identity(dim), format="csr")
        assert copies.has_canonical_format and (copies != expected).nnz == 0 and copies.nnz == expected.nnz


def test_a_points_strain_rows_are_the_strain_operators(model):
    """Made from its element alone before ``B`` is (B-bar: from ``B``), they equal ``B``'s rows
    to the bit."""
    points = np.random.default_rng(0).choice(model.n_qp, 5, replace=False)
    rows = [model.strain_rows(int(q)).toarray() for q in points]
    nc = rows[0].shape[0]
    for q, r in zip(points, rows):
        assert np.array_equal(r, model.B[q * nc:(q + 1) * nc].toarray())


def test_the_stiffness_by_node_pairs_equals_the_strain_operators_product(model):
    """``K`` from the gradients' products per pair of nodes (B-bar: the strains') equals
    ``B^T diag(w D) B`` of the strain operator, to round-off, and holds no exact zero."""
    K = model.stiffness()
    expected = model.B.T @ (forms.material_blocks(model.D, model.stiffness_weights()) @ model.B)
    assert abs(K - expected).max() <= 1e-14 * abs(expected).max()
    assert K.nnz == np.count_nonzero(K.data) and K.has_canonical_format


def test_a_faces_row_of_k_from_its_elements_equals_k(model):
    x = np.zeros(model.basis.N)
    x[model.basis.get_dofs(facets=model.rmesh.mesh.boundary_facets()[:7]).flatten()] = 1.0
    expected = model.stiffness() @ x
    assert np.abs(model.stiffness_times(x) - expected).max() <= 1e-13 * np.abs(expected).max()


def test_a_probe_at_a_node_reads_the_node_as_the_element_map_does(model):
    basis = model.basis
    node = basis.element_dofs[-1, basis.dx.shape[0] // 2] // model.dim  # an element's centre node
    x = basis.doflocs[:, model.dim * node]
    rows = value_probes(basis, x)
    assert rows.nnz == model.dim and np.array_equal(rows.indices, model.dim * node + np.arange(model.dim))
    u = np.random.default_rng(1).normal(size=basis.N)
    shifted = value_probes(basis, x + 1e-9 * np.abs(basis.doflocs).max())  # by the element's map
    assert np.abs(rows @ u - shifted @ u).max() <= 1e-6 * np.abs(u).max()


def test_the_kept_inverse_map_gives_the_bases_scikit_fem_gives():
    """A cell and a facet basis on the reference's mapping, which keeps the inverse Jacobian,
    the inverse map and the shape functions of the points last asked for, and of its vector
    element, which keeps its scalar function for the components, equal those on scikit-fem's own
    (its map, Jacobian and Newton iteration, at the reference's tolerance; ``ElementVector``)."""
    model = Model(get_case("thick_cylinder", {"dim": 3}))
    mesh, element = model.rmesh.mesh, model.element
    plain = MappingIsoparametric(mesh, mesh.elem(), mesh.bndelem)
    plain.invF = partial(MappingIsoparametric.invF, plain, newton_tol=INVF_TOL)
    for make, kwargs in ((ties.cell_basis, {}), (ties.facet_basis, {"facets": mesh.boundary_facets()[:40]})):
        ours = make(mesh, element, intorder=INTORDER, **kwargs)
        theirs = make(mesh, ElementVector(element.elem), mapping=plain, intorder=INTORDER, **kwargs)
        for i in (0, 40, 41, 42, 80):
            assert np.array_equal(ours.basis[i][0].grad, theirs.basis[i][0].grad)
            assert np.array_equal(np.asarray(ours.basis[i][0]), np.asarray(theirs.basis[i][0]))
        assert np.array_equal(ours.dx, theirs.dx)
        if make is ties.facet_basis:
            assert np.array_equal(np.asarray(ours.normals), np.asarray(theirs.normals))


def test_a_run_without_fields_has_the_same_histories_and_no_mesh():
    from reference_fem import solve

    case = get_case("rod_impact", {"t_end": 2e-5})
    with_mesh, without = solve(case), solve(case, fields=False)
    assert with_mesh.mesh is not None and without.mesh is None
    for name, values in with_mesh.history.items():
        assert np.array_equal(values, without.history[name])


#: the 3D moving load's histories (refine 1, the case's step: its cheapest run within 1 %) at steps
#: 75, 150 and 300, as the reference made them at 8035859, before the set-up was made cheaper (the
#: strains' product for K, scikit-fem's map, vector element and moving pressure's vector facet basis)
MOVING_LOAD_3D = {"mid_uz": (-8.2739208436027391e-07, -1.6288570618661269e-06, -2.2395636597384045e-07),
                  "q_uz": (-5.4019433422663523e-07, -1.1248336370486006e-06, -1.0397995763828745e-07)}


def test_the_3d_moving_load_has_the_histories_it_had():
    """Within 1e-11 of each probe's largest value (round-off through 300 steps: 2e-12)."""
    from reference_fem import solve

    result = solve(get_case("moving_load", {"dim": 3}), fields=False)
    for name, expected in MOVING_LOAD_3D.items():
        values = np.asarray(result.history[name])
        assert np.abs(values[[75, 150, 300]] - expected).max() <= 1e-11 * np.abs(values).max()
