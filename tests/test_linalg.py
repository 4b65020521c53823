"""SMFEM's factorization of SPD step matrices: banded Cholesky where the band is narrow."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from cases import get_case
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
