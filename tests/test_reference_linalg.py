"""The reference FEM's Newton tangents solved by CG on the elastic factors (reference_fem.linalg)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from cases import get_case
from reference_fem.linalg import PreconditionedTangent, factorize
from smfem.runs.registry import solve


def _spd(n, rng):
    R = sp.random(n, n, density=0.05, random_state=rng)
    return (R @ R.T + sp.identity(n) * 4).tocsc()


def test_a_tangent_by_cg_on_the_elastic_factors_equals_its_factorization():
    rng = np.random.default_rng(0)
    n, nc, n_y = 60, 3, 5
    A = _spd(n, rng)
    By = sp.random(n_y * nc, n, density=0.2, random_state=rng).tocsr()
    W = rng.normal(size=(n_y, nc, nc))
    blocks = -0.3 * np.einsum("qij,qkj->qik", W, W)  # a softening correction, symmetric
    tangent = (A + By.T @ sp.block_diag(list(blocks)) @ By).tocsc()
    t = PreconditionedTangent(A, factorize(A), By, blocks, lambda: factorize(tangent))
    r = rng.normal(size=n)
    x = t.solve(r)
    assert np.abs(x - factorize(tangent).solve(r)).max() <= 1e-8 * np.abs(x).max()
    assert 0 < t.iterations < n and not t.factorized


def test_a_tangent_cg_does_not_solve_within_its_limit_is_factorized_instead(monkeypatch):
    """(A near-singular tangent at a collapse: CG stalls.) The factors answer, and stay."""
    from reference_fem import linalg

    monkeypatch.setattr(linalg, "PCG_MAX_ITERATIONS", 2)
    rng = np.random.default_rng(1)
    n = 40
    A = _spd(n, rng)
    By = sp.identity(n, format="csr")
    blocks = -rng.uniform(0, 3.9, size=(n, 1, 1))  # softening, still positive definite
    tangent = (A + sp.diags(blocks.ravel())).tocsc()
    made = []
    t = PreconditionedTangent(A, factorize(A), By, blocks, lambda: made.append(1) or factorize(tangent))
    for seed in (2, 3):
        r = np.random.default_rng(seed).normal(size=n)
        assert np.abs(tangent @ t.solve(r) - r).max() <= 1e-10 * np.abs(r).max()
    assert t.factorized and made == [1]


# the first yielding steps: the strip's 14th of 3.2e-6 s, the plastic cylinder's 19th of 4e-5 s
@pytest.mark.parametrize("name, sets", [("notched_strip", {"refine": 1, "t_end": 6.4e-5}),
                                        ("thick_cylinder", {"plastic": True, "refine": 1, "t_end": 1.0e-3})])
def test_plastic_histories_are_the_factorized_tangents_to_the_solver_tolerance(name, sets):
    """The same Newton iterates, so the same histories (to 1e-9 of each probe's largest value),
    with one factorization (the elastic one) instead of one per yielding iteration."""
    case = get_case(name, sets)
    # auto, the default, is CG on a von Mises tangent (symmetric)
    runs = {how: solve("reference-2d", case, options={"linear_solver": how}) for how in ("auto", "superlu")}
    pcg, lu = runs["auto"], runs["superlu"]
    assert pcg.info["linear_solver"] == "auto" and pcg.info["factorizations"] == 1 < lu.info["factorizations"]
    assert pcg.info["cg_iterations"] > 0 and pcg.info["cg_fallbacks"] == 0
    assert list(pcg.iterations) == list(lu.iterations)
    for probe, values in lu.history.items():
        scale = np.abs(values).max() or 1.0
        assert np.abs(pcg.history[probe] - values).max() <= 1e-9 * scale, probe


def test_an_unknown_linear_solver_is_refused_in_one_line(capsys):
    from smfem.cli import main

    assert main(["run", "notched_strip", "--solver", "reference", "--set", "linear_solver=mumps"]) == 2
    err = capsys.readouterr().err
    assert "linear_solver" in err and "superlu" in err and len(err.strip().splitlines()) == 1


def test_the_registry_names_the_reference_linear_solvers_and_the_explicit_engine_has_none():
    from reference_fem.linalg import LINEAR_SOLVERS
    from smfem.runs.registry import lookup

    assert lookup("reference").options()["linear_solver"].choices == LINEAR_SOLVERS
    assert "linear_solver" not in lookup("reference-explicit").options()


def test_bbar_frees_the_implicit_reference_of_locking_in_plastic_flow():
    """The notched cylinder's plastic flow is nearly incompressible: the standard 9-node element
    locks, B-bar (the explicit truth's element) does not. Against the stored truth (first 12 ms)
    the B-bar run is nearer, and says so in its summary."""
    from smfem.runs.errors import history_errors
    from smfem.studies import stored

    truth = stored.read(stored.directory("notched_cylinder"))
    case = get_case("notched_cylinder", {"refine": 1, "t_end": 0.012})
    err = {}
    for bbar in (False, True):
        result = solve("reference-2d", case, options={"bbar": bbar})
        assert result.info["bbar"] is bbar
        err[bbar] = max(history_errors(result.t, result.history[p], truth.t, truth.values[p])[0]
                        for p in ("D_ur", "E_ur", "F_ur"))
    assert err[True] < 0.8 * err[False], err
