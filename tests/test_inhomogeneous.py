"""Material varying along x3: coupling integrals, harmonic selection, the coupled direct solve."""

import dataclasses
import math

import numpy as np
import pytest
import scipy.sparse as sp

from cases import get_case
from cases.geometry import Probe, interval_fourier
from smfem import inhomogeneity
from smfem.model import Model
from smfem.solver import solve
from helpers import turned_cutouts


def closed_form(l, m, intervals, body, length, product):
    """int over intervals of cos*cos (ring, psi1) or sin*sin (prism, psi1), product-to-sum."""
    sign = 1.0 if product == "cos" else -1.0
    c = lambda n: interval_fourier(intervals, abs(n), "cos", body, length)
    return 0.5 * (c(l - m) + sign * c(l + m))


@pytest.mark.parametrize("name", ["notched_cylinder", "notched_strip"])
def test_coupling_integrals_are_exact(name):
    """Quadrature on the pieces between cut-out edges against closed-form integrals:
    int f psi_l psi_m = int psi_l psi_m - (1 - contrast) int_cut psi_l psi_m."""
    case = get_case(name, {"plastic": False, "contrast": 1e-3})
    model = Model(case)
    e = int(np.argmin(model.factor.min(axis=1)))  # an element inside the cut-out
    assert model.factor[e].min() == case.contrast
    modes = model.modes[:6]
    I = inhomogeneity.coupling_integrals(modes, case, model.factor[e:e + 1], model.x3, model.x3_weights)
    L = case.length
    whole = ((0.0, 2 * math.pi if case.body == "ring" else L),)
    product = "cos" if case.body == "ring" else "sin"
    for i, a in enumerate(modes):
        for j, b in enumerate(modes):
            exact = closed_form(a.l, b.l, whole, case.body, L, product) - (1 - case.contrast) * closed_form(
                a.l, b.l, case.cutouts[0].x3_intervals, case.body, L, product)
            assert I[i, j, 0, 0, 0] == pytest.approx(exact, abs=1e-12 * L)


def test_symmetric_cutouts_select_even_cosines_and_the_strip_odd_harmonics():
    cyl = Model(get_case("notched_cylinder", {"plastic": False}))
    assert cyl.harmonics_used() == [f"{l}c" for l in range(0, 40, 2)]
    strip = Model(get_case("notched_strip", {"plastic": False}))
    assert strip.harmonics_used() == [str(l) for l in range(1, 121, 2)]
    assert cyl.coupling and strip.coupling


def test_turned_cutouts_turn_the_response():
    """Cut-outs turned by 30 deg need both families and cross-family coupling; probes turned with
    them reproduce the original histories."""
    case = get_case("notched_cylinder", {"plastic": False, "t_end": 5e-3})
    turn = math.pi / 6
    turned = dataclasses.replace(
        turned_cutouts(case, turn),
        probes=tuple(Probe(p.name, p.kind, p.field, p.component, point=(*p.point[:2], p.point[2] + turn))
                     for p in case.probes),
    )
    base, rot = solve(case, with_fields=False), solve(turned, with_fields=False)
    assert any(h.endswith("s") for h in rot.info["harmonics_used"])
    for name, h in base.history.items():
        assert np.abs(rot.history[name] - h).max() < 1e-6 * np.abs(h).max(), name


def test_coupled_run_reports_the_direct_solve():
    result = solve(get_case("notched_strip", {"plastic": False, "t_end": 3.2e-5, "harmonics": 40}), with_fields=False)
    assert result.info["solve"].startswith("direct") and result.info["factorizations"] == 1
    assert np.all(np.isfinite(result.history["mid_uz"])) and result.history["mid_uz"][-1] < 0


def relative_error(a, b):
    return max(np.abs(a[k] - b[k]).max() / np.abs(b[k]).max() for k in b if not k.startswith("peps"))


def test_notched_cylinder_converges_in_harmonics():
    """Elastic probes with 10, 20, 40 harmonics against 80: 4.7 %, 1.4 %, 0.4 % (measured)."""
    runs = {H: solve(get_case("notched_cylinder", {"plastic": False, "harmonics": H}), with_fields=False).history
            for H in (10, 20, 40, 80)}
    errors = [relative_error(runs[H], runs[80]) for H in (10, 20, 40)]
    assert errors[0] > errors[1] > errors[2] and errors[2] < 0.01
    assert np.log(errors[0] / errors[2]) / np.log(4) > 1.5  # observed order in 1/H


def test_notched_strip_static_deflection_converges_in_harmonics():
    """The narrow notch makes the series converge slowly but steadily (static mid-span u_z)."""
    import scipy.sparse.linalg as sla

    from smfem.probes import ProbeSet
    from smfem.stacking import stacked

    def static(H):
        case = get_case("notched_strip", {"plastic": False, "harmonics": H})
        model = Model(case)
        K, _, Q, _, _ = stacked(model)
        u = sla.spsolve(K.tocsc(), Q)
        return ProbeSet(model, case.probes[:1]).evaluate(u, u)[0]

    values = {H: static(H) for H in (20, 40, 80, 160)}
    errors = [abs(values[H] / values[160] - 1) for H in (20, 40, 80)]
    assert errors[0] > errors[1] > errors[2] and errors[2] < 0.03


def test_contrast_1e4_against_1e8_changes_the_probes_less_than_half_a_percent():
    """Plastic notched cylinder: the cut-out material's contrast barely matters, and both converge."""
    a = solve(get_case("notched_cylinder", {"contrast": 1e-4}), with_fields=False)
    b = solve(get_case("notched_cylinder", {"contrast": 1e-8}), with_fields=False)
    assert a.converged and b.converged and b.info["iterations_max"] < 20
    assert relative_error(a.history, b.history) < 0.005


def test_the_harmonic_coupling_is_exactly_sparse():
    """Different harmonics couple only through the cut-out elements (elsewhere they are
    orthogonal along x3): the off-diagonal blocks hold entries of those elements' dofs only,
    and no stored zeros; the batched assembly equals the pair-by-pair one."""
    from smfem import assembly, element, fourier

    model = Model(get_case("notched_strip", {"harmonics": 12}), nonlinear=True)
    K = model.coupled_stiffness()
    cut = np.flatnonzero((model.factor != 1.0).any(axis=1))
    assert 0 < len(cut) < model.mesh.n_elements / 2 and model.coupling
    offsets = np.cumsum([0] + [s.T.shape[1] for s in model.systems])
    cut_dofs = np.unique(assembly.element_dofs(model.mesh.elements[cut]))
    for i, j in model.coupling:
        block = K[offsets[i]:offsets[i + 1], offsets[j]:offsets[j + 1]]
        M = model.coupled_mass[offsets[i]:offsets[i + 1], offsets[j]:offsets[j + 1]]
        Si, Sj = model.systems[i], model.systems[j]
        assert set(np.unique(block.nonzero()[0])) <= set(Si.T[cut_dofs].nonzero()[1])
        # one pair the plain way: every element, assembled and mapped on its own
        Dw = assembly.weighted_elasticity(model.D, model.integrals(i, j))
        p, q = (fourier.wavenumber(s.mode, model.body, model.length) for s in (Si, Sj))
        full = assembly.assemble(element.element_stiffness(model.ops, p, Dw, q), model.mesh.elements, model.mesh.n_nodes)
        plain = (Si.T.T @ full @ Sj.T).toarray()
        assert np.abs(block.toarray() - plain).max() <= 1e-12 * np.abs(plain).max(initial=1.0)
        mass = (Si.T.T @ sp.diags(model.full_mass(i, j)) @ Sj.T).toarray()
        assert np.abs(M.toarray() - mass).max() <= 1e-12 * np.abs(mass).max(initial=1.0)
        assert np.all(block.data != 0) and np.all(M.data != 0)


@pytest.mark.parametrize("name, sets", [("notched_strip", {"harmonics": 24}), ("notched_cylinder", {}),
                                        ("notched_cylinder", {"plastic": False})])
def test_the_matrix_free_operator_equals_the_assembled_coupled_matrices(name, sets):
    """K x and M x through the cut-outs' x3 points (smfem.coupling) against the assembled
    coupled stiffness and mass, on random amplitudes."""
    from smfem.coupling import StackedOperator
    from smfem.stacking import stacked

    model = Model(get_case(name, sets), nonlinear=case_is_plastic(name, sets))
    K, M, _, _, _ = stacked(model)
    op = StackedOperator(model)
    x = np.random.default_rng(0).normal(size=K.shape[0])
    assert np.abs(K @ x - op.K(x)).max() <= 1e-12 * np.abs(K @ x).max()
    assert np.abs(M @ x - op.M(x)).max() <= 1e-12 * np.abs(M @ x).max()


def case_is_plastic(name, sets) -> bool:
    return get_case(name, sets).material.plastic


def test_matrix_free_iterations_equal_the_coupled_factorization():
    """Conjugate gradients on the matrix-free coupled system, preconditioned by the diagonal
    blocks, give the direct factorization's histories (plastic strip, elastic cylinder)."""
    from smfem.options import SolverOptions

    for case in (get_case("notched_strip", {"harmonics": 40, "t_end": 9.6e-5, "tol": 1e-10}),
                 get_case("notched_cylinder", {"plastic": False, "t_end": 1e-3, "tol": 1e-10})):
        direct = solve(case, with_fields=False)
        free = solve(case, SolverOptions(iteration_matrix="matrix-free"), with_fields=False)
        assert "conjugate gradients" in free.info["solve"] and free.info["krylov_iterations"] > 0
        for name, h in direct.history.items():  # plastic strains just past first yield are the touchiest
            tol = 1e-6 if name.startswith("peps") else 1e-8
            assert np.abs(free.history[name] - h).max() <= tol * max(np.abs(h).max(), 1e-30), name


def test_the_woodbury_form_solves_the_coupled_system():
    """The notched strip's coupled K + a0 M as the homogeneous block-diagonal matrix minus the
    notch's low-rank correction (smfem.woodbury): its rank is set by the notch's x3 points, not
    by the harmonics, and its solves are those of the assembled matrix. Measured residuals:
    2e-13 at 24 harmonics, 1e-9 at 120 (the contrast 1e-6 cancels digits)."""
    from smfem import coupled_solve, woodbury
    from smfem.coupling import StackedOperator
    from smfem.newmark import Constants

    for harmonics, tol in ((120, 1e-7), (24, 1e-11)):
        case = get_case("notched_strip", {"harmonics": harmonics})
        model = Model(case, nonlinear=True)
        a0 = Constants.of(case.dt).a0
        W = woodbury.CutoutWoodbury(model, a0)
        assert W.rank <= woodbury.rank_bound(model)
        b = np.random.default_rng(1).normal(size=(model.n_dof))
        x = W.solve(b)
        op = StackedOperator(model)
        assert np.linalg.norm(op.K(x) + a0 * op.M(x) - b) <= tol * np.linalg.norm(b)
    # by predicted cost: the whole factorization at 24 harmonics, the low-rank form at 120 (its
    # plastic run 0.1-0.2 s cheaper so, a loaded host) and at 400
    assert coupled_solve.choose(model, 1000, 10**12)[0] == "whole"
    assert coupled_solve.choose(Model(get_case("notched_strip"), nonlinear=True), 493, 10**12)[0] == "woodbury"
    assert coupled_solve.choose(Model(get_case("notched_strip", {"harmonics": 400}), nonlinear=True), 1000, 10**12)[0] == "woodbury"


@pytest.mark.parametrize("name, sets, turn", [("notched_strip", {"harmonics": 24}, 0.0),
                                              ("moving_load_notched", {"harmonics": 12, "element": "quad9"}, 0.0),
                                              ("notched_cylinder", {"harmonics": 12, "refine": 1}, 0.5)])
def test_the_woodbury_capacitance_is_its_definition(name, sets, turn):
    """``S^-1`` of the Woodbury form (its lower triangle, formed through the kernel of unit
    amplitudes per basis type and pair of points) against ``S = I - V A_h^-1 V'`` formed from
    ``V`` applied to every unit vector, on a prism with its in-plane and x3 dofs and on a ring
    with both families (the cut-outs' contrast 1e-6 costs S^-1 digits: 6e-10 on the ring)."""
    from smfem import woodbury
    from smfem.newmark import Constants

    case = turned_cutouts(get_case(name, sets), turn)
    model = Model(case, nonlinear=True)
    W = woodbury.CutoutWoodbury(model, Constants.of(case.dt).a0)
    V = np.stack([W._V(x).ravel() for x in np.eye(model.n_dof)], axis=1)  # (rank, n_dof)
    S = np.eye(W.rank) - V @ W.base.solve(V.T)
    lower = np.tril_indices(W.rank)
    expected = np.linalg.inv(S)[lower]
    assert np.abs(W.inverse[lower] - expected).max() <= 1e-8 * np.abs(expected).max()


def test_a_run_with_the_woodbury_form_equals_the_sparse_factorization(monkeypatch):
    from smfem import coupled_solve

    case = get_case("notched_strip", {"harmonics": 40, "t_end": 9.6e-5, "tol": 1e-10})
    monkeypatch.setattr(coupled_solve, "choose", lambda model, solves, nnz: ("whole", {}))
    sparse = solve(case, with_fields=False)
    monkeypatch.setattr(coupled_solve, "choose", lambda model, solves, nnz: ("woodbury", {}))
    low_rank = solve(case, with_fields=False)
    assert "Woodbury" in low_rank.info["solve"] and "Woodbury" not in sparse.info["solve"]
    for name, h in sparse.history.items():
        tol = 1e-6 if name.startswith("peps") else 1e-8
        assert np.abs(low_rank.history[name] - h).max() <= tol * max(np.abs(h).max(), 1e-30), name


def test_every_form_of_the_coupled_solve_gives_the_same_elastic_histories(monkeypatch):
    """The elastic path solves the coupled system with the form of least predicted cost
    (smfem.coupled_solve): whole, Woodbury or warm-started conjugate gradients. The algebra
    must not change the answer: the same histories to 1e-9 relative."""
    from smfem import coupled_solve

    case = get_case("notched_strip", {"plastic": False, "harmonics": 40, "t_end": 9.6e-5})
    runs = {}
    for form in ("whole", "woodbury", "krylov"):
        monkeypatch.setattr(coupled_solve, "choose", lambda model, solves, nnz, form=form: (form, {}))
        runs[form] = solve(case, with_fields=False)
    assert "Woodbury" in runs["woodbury"].info["solve"] and "conjugate gradients" in runs["krylov"].info["solve"]
    for form in ("woodbury", "krylov"):
        for name, h in runs["whole"].history.items():
            assert np.abs(runs[form].history[name] - h).max() <= 1e-9 * np.abs(h).max(), (form, name)


def test_the_field_marks_the_cut_out_cells(tmp_path):
    """fields.vtu carries ``solid``: 0 on the cells of the cut-outs' fictitious material, 1 on the
    body; the fictitious cells are where the field's largest velocities are, and the 3-D view
    leaves them out."""
    import meshio

    from reports.view3d import render_field

    case = get_case("notched_cylinder", {"t_end": 2e-3, "plastic": False})
    mesh = solve(case).mesh
    solid = mesh.cell_data["solid"][0]
    assert set(np.unique(solid)) == {0, 1}
    hexes = mesh.cells[0].data
    speed = np.linalg.norm(mesh.point_data["velocity"], axis=1)
    body_nodes = np.unique(hexes[solid == 1])
    assert speed.max() > 1.5 * speed[body_nodes].max()  # measured 9.9 against 5.5 m/s: the fictitious material
    vtu = tmp_path / "field.vtu"
    meshio.write(vtu, mesh)
    assert render_field(vtu, tmp_path / "field.png", "notched", "m").stat().st_size > 10_000
    whole = get_case("thick_cylinder", {"t_end": 4e-4})
    assert np.all(solve(whole).mesh.cell_data["solid"][0] == 1)


def test_the_woodbury_form_at_fewer_point_combinations_solves_as_at_the_points(monkeypatch):
    """The cut-out's points replaced by combinations that span the modes' values there
    (smfem.woodbury.point_combinations): a lower rank and the same solves to the form's own
    accuracy (the notched cylinder, whose ring modes share a symmetry: 73 points, 19
    combinations; measured: residuals 3.1e-9 both, against 4e-10 of the whole factorization,
    the contrast 1e-6 costing digits; the two 5e-10 apart, each 8e-9 from the whole's)."""
    from smfem import woodbury
    from smfem.coupling import StackedOperator
    from smfem.newmark import Constants

    case = get_case("notched_cylinder", {"harmonics": 20})
    model = Model(case, nonlinear=True)
    a0 = Constants.of(case.dt).a0
    b = np.random.default_rng(1).normal(size=model.n_dof)
    combined = woodbury.CutoutWoodbury(model, a0)
    x3, w, excess = woodbury.cutout_points(model)
    # each point by itself, weighted: the form before the combinations
    monkeypatch.setattr(woodbury, "point_combinations", lambda m: (x3, np.diag(np.sqrt(w)), excess))
    points = woodbury.CutoutWoodbury(model, a0)
    assert combined.F.shape[0] < points.F.shape[0] == len(x3) and combined.rank < points.rank
    x, y = combined.solve(b), points.solve(b)
    op = StackedOperator(model)
    residual = lambda v: np.linalg.norm(op.K(v) + a0 * op.M(v) - b) / np.linalg.norm(b)
    assert residual(x) <= 1e-8 and residual(x) <= 1.5 * residual(y)
    assert np.abs(x - y).max() <= 1e-8 * np.abs(y).max()


def rule_error(x: np.ndarray, w: np.ndarray, omega: float) -> float:
    """Largest error of ``x, w`` on ``cos(o x)`` and ``sin(o x)`` over [-1, 1], ``o <= omega``
    (every 0.25 over the top 30 %), summed in long double so the sums' round-off does not count."""
    o = np.concatenate([np.linspace(1e-3, 0.7 * omega, 40), np.arange(0.7 * omega, omega, 0.25),
                        [omega]])
    o, x, w = o.astype(np.longdouble), x.astype(np.longdouble), w.astype(np.longdouble)
    phase = o[:, None] * x[None, :]
    cos_error = np.abs(np.cos(phase) @ w - 2 * np.sin(o) / o).max()
    return float(max(cos_error, np.abs(np.sin(phase) @ w).max()))


def test_x3_rule_integrates_every_frequency_up_to_omega():
    """The rule's count integrates to 1e-14 over omega 1-300, twice as many points too; two fewer
    transplanted points (its margin and one) fail somewhere, so the check resolves the count."""
    tight = []
    for omega in np.geomspace(1.0, 300.0, 16):
        x, w = inhomogeneity.x3_rule(omega)
        assert rule_error(x, w, omega) < 1e-14, omega
        assert rule_error(*inhomogeneity.x3_rule(omega, 2.0), omega) < 1e-14, omega
        n = inhomogeneity.transplanted_points_needed(omega)
        if n < inhomogeneity.gauss_points_needed(omega):
            assert len(x) == n
            tight.append(rule_error(*inhomogeneity.transplanted(n - 2), omega) > 1e-14)
    assert any(tight) and len(tight) >= 8


def test_x3_rule_takes_fewer_points_than_gauss_legendre_at_large_omega():
    """The transplanted rule's count against Gauss-Legendre's: about 1.45 times fewer at
    omega 1000 and more (pi/2, the band limit's, is the most a map can gain)."""
    for omega in (1000.0, 2000.0):
        plain = inhomogeneity.gauss_points_needed(omega)
        ratio = plain / inhomogeneity.transplanted_points_needed(omega)
        assert 1.4 < ratio < math.pi / 2
