"""SMFEM's factorizations of its step matrices (smfem/linalg.py)."""

import numpy as np
import scipy.sparse as sp

from smfem import linalg


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
