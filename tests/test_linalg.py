"""SMFEM's factorization of SPD step matrices: banded Cholesky where the band is narrow."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from cases import get_case
from smfem import linalg
from smfem.linalg import BandedCholesky, block_diagonal, factorize_spd, stacked_step, step_blocks
from smfem.model import Model
from smfem.newmark import Constants


def test_a_rod_matrix_goes_banded_and_solves_like_lu():
    case = get_case("rod_impact", {"refine": 2})
    s = Model(case).systems[0]
    A = s.K + sp.diags(Constants.of(case.dt).a0 * s.M)
    f = factorize_spd(A)
    assert isinstance(f, BandedCholesky)
    b = np.random.default_rng(0).normal(size=(A.shape[0], 3))
    x = f.solve(b)
    assert np.abs(x - sla.splu(A.tocsc()).solve(b)).max() <= 1e-10 * np.abs(x).max()


def test_a_band_wider_than_the_lu_or_an_indefinite_matrix_goes_to_lu():
    """An arrow matrix (a full first row and column) has a band as wide as itself after any
    banded ordering, while a minimum-degree LU of it has no fill: LU. An indefinite matrix fails
    the Cholesky: LU, with pivoting."""
    rng = np.random.default_rng(1)
    arrow = sp.lil_matrix((60, 60))
    arrow.setdiag(60.0 + rng.random(60))
    arrow[0, 1:], arrow[1:, 0] = 1.0, 1.0
    indefinite = sp.diags(np.r_[np.ones(59), -1.0]).tocsr()
    for A in (sp.csr_matrix(arrow), indefinite):
        f = factorize_spd(A)
        assert not isinstance(f, BandedCholesky)
        b = rng.normal(size=60)
        assert np.allclose(A @ f.solve(b), b)


def test_block_diagonal_and_the_stacked_step_matrix_are_scipys():
    """The joined index arrays against scipy's block_diag: blocks of any shape, an empty one,
    a block with an empty row; and the stacked K + a0 M against the blocks' one by one."""
    rng = np.random.default_rng(0)
    blocks = [sp.random(3, 5, density=0.4, random_state=1), sp.csr_matrix((2, 2)),
              sp.random(4, 1, density=0.5, random_state=2), sp.random(6, 6, density=0.3, random_state=3)]
    assert (block_diagonal(blocks) != sp.block_diag(blocks, format="csr")).nnz == 0
    assert block_diagonal(blocks).shape == (15, 14)
    pairs = [(sp.random(n, n, density=0.5, random_state=n) + sp.eye(n), rng.random(n)) for n in (3, 1, 4)]
    expected = sp.block_diag(list(step_blocks(pairs, 2.5)), format="csr")
    assert abs(stacked_step(pairs, 2.5) - expected).max() == 0.0


def _spd(n: int, band: int, seed: int) -> sp.csr_matrix:
    rng = np.random.default_rng(seed)
    A = sp.diags([rng.uniform(0.1, 1.0, n - k) for k in range(1, band + 1)], list(range(1, band + 1)), shape=(n, n))
    return sp.csr_matrix(A + A.T + sp.diags(np.full(n, 2.0 * band + 1.0)))


def test_banded_blocks_are_solved_in_one_call_with_the_blocks_answers():
    """BlockFactors joins small banded blocks into one band (narrower ones padded): one dpbtrs
    solves them all, to the per-block answers; a block in a sparse LU, or a band past the
    limit, leaves them block by block."""
    blocks = [_spd(40, 3, 1), _spd(25, 1, 2), _spd(60, 5, 3)]
    factors = linalg.BlockFactors(iter(blocks))
    assert factors.joined is not None and factors.joined.factor.shape == (6, 125)
    b = np.random.default_rng(4).normal(size=(125, 2))
    by_block = np.concatenate([f.solve(b[a:c]) for f, a, c in zip(factors.factors, factors.offsets[:-1], factors.offsets[1:])])
    assert np.allclose(factors.solve(b), by_block, rtol=1e-14, atol=0.0)
    assert np.allclose(sp.block_diag(blocks) @ factors.solve(b), b)
    assert linalg.BlockFactors(iter(blocks), factorize=linalg.sparse_lu).joined is None
    assert linalg.joined_band(factors.factors[:1]) is None
    saved, linalg.JOINED_BAND_BYTES = linalg.JOINED_BAND_BYTES, 8 * 6 * 124
    try:
        assert linalg.joined_band(factors.factors) is None
    finally:
        linalg.JOINED_BAND_BYTES = saved
