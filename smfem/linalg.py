"""Factorizations of SMFEM's step matrices ``K + a0 M``.

These are symmetric positive definite (a stiffness plus a positive mass, the supports
removed). Sections are long and thin (a rod, a strip) or small, so after a reverse
Cuthill-McKee ordering their bandwidth is often small: LAPACK's banded Cholesky then solves
with fewer operations than a sparse LU and none of its pivoting (rod, refine 4, 16k dof:
3.6 ms per solve against 6.9 ms). Where harmonics couple, the band is wide and SuperLU in a
minimum-degree ordering is faster.
"""

from __future__ import annotations

import os

import numpy as np
import scipy.linalg as la
from scipy.linalg.lapack import dpbtrs
import scipy.sparse as sp
import scipy.sparse.linalg as sla
from scipy.sparse.csgraph import reverse_cuthill_mckee

#: the largest band (entries n x (bandwidth + 1)) stored for a banded Cholesky
MAX_BAND_ENTRIES = 30_000_000


class BandedCholesky:
    """``A = L L'`` of a symmetric positive definite ``A`` in a reverse Cuthill-McKee ordering."""

    def __init__(self, Ap: sp.coo_matrix, perm: np.ndarray, bandwidth: int):
        """``Ap``: the matrix already reordered by ``perm``, whose band is ``bandwidth`` wide.
        Raises ``LinAlgError`` where it is not positive definite."""
        upper = Ap.row <= Ap.col
        band = np.zeros((bandwidth + 1, Ap.shape[0]))
        band[bandwidth + Ap.row[upper] - Ap.col[upper], Ap.col[upper]] = Ap.data[upper]
        self.factor, self.perm = la.cholesky_banded(band, check_finite=False), perm

    @classmethod
    def of(cls, factor: np.ndarray, perm: np.ndarray) -> BandedCholesky:
        """The factorization whose upper band ``factor`` and ordering ``perm`` are given."""
        made = cls.__new__(cls)
        made.factor, made.perm = factor, perm
        return made

    def solve(self, b: np.ndarray) -> np.ndarray:
        # LAPACK's dpbtrs directly: scipy's cho_solve_banded checks its arguments on every call,
        # a third of a small section's solve (thick cylinder, 608 dof: 61 -> 41 us)
        y, info = dpbtrs(self.factor, b[self.perm])
        if info:
            raise la.LinAlgError(f"dpbtrs: illegal argument {-info}")
        x = np.empty_like(y)
        x[self.perm] = y
        return x


def factorize_spd(A: sp.spmatrix):
    """A factorization of the symmetric positive definite ``A`` with ``solve(b)`` (``b`` one
    or more columns): banded Cholesky where its band holds at most 1.5 times the nonzeros of a
    sparse LU (:func:`sparse_lu`), else that LU. Measured (one solve, ms, banded / LU): dome
    refine 4 0.097 / 0.184 (band 181k, LU 181k entries), thick cylinder refine 4, 80 harmonics
    0.094 / 0.175 (40k, 64k); notched strip 0.81 / 0.32 (1.6M, 442k)."""
    A = sp.csr_matrix(A)
    perm = reverse_cuthill_mckee(A, symmetric_mode=True)
    coo = A[perm][:, perm].tocoo()
    bandwidth = int(np.abs(coo.row - coo.col).max(initial=0))
    band = A.shape[0] * (bandwidth + 1)
    lu = sparse_lu(A)
    if band > MAX_BAND_ENTRIES or band > 1.5 * lu.nnz:
        return lu
    try:
        return BandedCholesky(coo, perm, bandwidth)
    except la.LinAlgError:  # not positive definite after all: the general path
        return sparse_lu(A, symmetric=False)


def sparse_lu(A: sp.spmatrix, symmetric: bool = True):
    """SuperLU of ``A``; for a symmetric positive definite ``A`` in a minimum-degree ordering of
    ``A + A'`` with diagonal pivots (the notched strip at 400 harmonics: 10.4M nonzeros in the
    factors and 9.5 ms per solve, against 23M and 20 ms in the default column ordering)."""
    if not symmetric:
        return sla.splu(sp.csc_matrix(A))
    return sla.splu(sp.csc_matrix(A), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                    options=dict(SymmetricMode=True))


def step_blocks(pairs, a0: float):
    """``K + a0 M`` of each mode's (stiffness, lumped mass diagonal) in ``pairs``, one by one."""
    return (K + sp.diags(a0 * M) for K, M in pairs)


def stacked_step(pairs, a0: float) -> sp.csr_matrix:
    """``K + a0 M`` of every mode's (stiffness, lumped mass diagonal) in ``pairs``, on the
    diagonal of one matrix."""
    stiffness, mass = zip(*pairs)
    return block_diagonal(stiffness) + sp.diags(a0 * np.concatenate(mass))


def block_diagonal(blocks) -> sp.csr_matrix:
    """The CSR matrix with ``blocks`` (sparse, any shape) on its diagonal, their index arrays
    shifted and joined: scipy's ``block_diag`` converts each block to COO and back, which
    costs more than the joining where there are hundreds of small blocks (one per harmonic)."""
    blocks = [sp.csr_matrix(b) for b in blocks]
    rows, cols = (np.cumsum([0] + [b.shape[axis] for b in blocks]) for axis in (0, 1))
    stored = np.cumsum([0] + [b.nnz for b in blocks])
    indptr = np.concatenate([[0]] + [b.indptr[1:] + n for b, n in zip(blocks, stored)])
    indices = np.concatenate([b.indices + c for b, c in zip(blocks, cols)])
    data = np.concatenate([b.data for b in blocks])
    return sp.csr_matrix((data, indices, indptr), shape=(rows[-1], cols[-1]))


#: the largest joined band (bytes) :class:`BlockFactors` keeps beside its blocks' factors, for
#: solving them all in one call
JOINED_BAND_BYTES = 64 * 2**20


def joined_band(factors: list) -> BandedCholesky | None:
    """One banded Cholesky factor of the block-diagonal matrix whose blocks ``factors`` are
    (all :class:`BandedCholesky`; the narrower bands padded with zeros to the widest), or None
    where a block is not banded or the joined band would pass :data:`JOINED_BAND_BYTES`.
    A block-diagonal matrix is banded with its widest block's band, and its factor is the
    blocks' factors side by side: one ``dpbtrs`` then solves every block, where a call per
    block cost more than its arithmetic (the pulse at 160 harmonics, 41 blocks: 20 us a call,
    1.34 of the run's 2.5 CPU s)."""
    if len(factors) < 2 or not all(isinstance(f, BandedCholesky) for f in factors):
        return None
    width = max(f.factor.shape[0] for f in factors)
    sizes = [f.factor.shape[1] for f in factors]
    if 8 * width * sum(sizes) > JOINED_BAND_BYTES:
        return None
    band = np.zeros((width, sum(sizes)), order="F")
    offsets = np.cumsum([0] + sizes)
    for f, a, b in zip(factors, offsets[:-1], offsets[1:]):
        band[width - f.factor.shape[0]:, a:b] = f.factor
    return BandedCholesky.of(band, np.concatenate([f.perm + a for f, a in zip(factors, offsets[:-1])]))


class BlockFactors:
    """Factors of a block-diagonal matrix, one per diagonal block, ``solve(b)`` block by block:
    a block's factorization takes its own unknowns' memory and fill only, never a copy of the
    whole matrix; ``factors``, each block's; ``nbytes``, what they hold. Where every block is
    banded and small, their bands are also joined into one (:func:`joined_band`), which solves
    them all in one call.

    Parameters
    ----------
    blocks : the diagonal blocks (sparse, square), in order: an iterable, so that each can be
        made when it is factorized
    factorize : ``factorize(A)``, a factorization with ``solve``
    """

    def __init__(self, blocks, factorize=factorize_spd):
        self.factors, self.nbytes, sizes = [], 0, [0]
        for A in blocks:
            self.factors.append(factorize(A))
            self.nbytes += factor_bytes(self.factors[-1], A.dtype.itemsize)
            sizes.append(A.shape[0])
        self.offsets = np.cumsum(sizes)
        self.joined = joined_band(self.factors)
        if self.joined is not None:
            self.nbytes += self.joined.factor.nbytes

    def solve(self, b: np.ndarray) -> np.ndarray:
        if self.joined is not None:
            return self.joined.solve(b)
        return np.concatenate([f.solve(b[a:c]) for f, a, c in zip(self.factors, self.offsets[:-1], self.offsets[1:])])


def factor_bytes(factor, itemsize: int = 8) -> int:
    """Bytes a factorization of a matrix of ``itemsize``-byte entries holds: a SuperLU's
    nonzeros with their row indices, a banded Cholesky's band."""
    if isinstance(factor, BandedCholesky):
        return factor.factor.nbytes
    return factor.nnz * (itemsize + 4)


def available_bytes() -> int:
    """The memory the machine has available now, bytes: ``MemAvailable`` of /proc/meminfo
    (Linux: free memory plus the caches it can drop), else the free pages ``os.sysconf``
    reports."""
    try:
        with open("/proc/meminfo") as f:
            lines = f.read().splitlines()
    except OSError:  # not Linux
        lines = []
    for line in lines:
        if line.startswith("MemAvailable:"):
            return int(line.split()[1]) * 1024
    return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
