"""Each mode's reduced stiffness and lumped mass as a combination of a few matrices built once.

Mode ``i``'s stiffness sums over the elements ``sum_ab I_ab (C_ab0 + p C_ab1 + p^2 C_ab2)``
(:func:`smfem.assembly.element_terms`; ``p`` its wavenumber, ``I_ab`` the x3 integrals of the
basis types' products weighted by the element's factor f). The elements share a few profiles
f(x3) (one where the body is the same all along x3), and ``I`` depends on an element only
through its profile ``g``, so

    K_i = sum_(g, a, b, k) I_ab(i, g) p_i^k G_gabk,

``G_gabk`` the terms of the elements of profile ``g`` assembled and reduced by the mode's
constraint map ``T``. The lumped mass likewise: ``M_i = sum_(g, a) I_aa(i, g) m_ga``. Modes
that share a map share these matrices and one sparsity pattern, and each mode's block is one
small product of its coefficients with them: its data array, where assembling each mode element
by element and reducing it by sparse products cost milliseconds a mode in scipy's bookkeeping
(benchmarks/README.md, ``coupled_profile.py``).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from . import assembly


#: the most matrices :class:`SharedBlocks` holds per profile: four pairs of basis types times
#: three powers of the wavenumber
TERMS_PER_PROFILE = 12


def pays(n_modes: int, n_profiles: int) -> bool:
    """Whether ``n_modes`` that share a map should share its :class:`SharedBlocks`: where they are
    at least as many as the matrices it holds at most, so that it never takes more memory than
    their blocks (a batch of one harmonic is assembled by itself)."""
    return n_modes >= TERMS_PER_PROFILE * n_profiles


def terms_by_power(ops, D: np.ndarray) -> tuple[np.ndarray, list[tuple[int, int, int]]]:
    """The element matrices of a mode's block with itself by basis types and power of ``p``:
    ``(ne, d, d, n_terms)`` and each term's ``(a, b, k)`` (:func:`smfem.assembly.element_terms`
    with ``q = p``: ``p^u q^v = p^(u + v)``)."""
    C, terms = assembly.element_terms(ops, D)
    keys = sorted({(a, b, u + v) for a, b, u, v in terms})
    merged = np.zeros(C.shape[:1] + C.shape[2:] + (len(keys),))
    for n, (a, b, u, v) in enumerate(terms):
        merged[..., keys.index((a, b, u + v))] += C[:, n]
    return merged, keys


class SharedBlocks:
    """The reduced stiffness and lumped mass of the modes that share one constraint map.

    Parameters
    ----------
    terms : ``(ne, d, d, n_terms)`` element matrices and their ``(a, b, k)``
        (:func:`terms_by_power`)
    profile : (ne,) each element's profile, ``0 ... n_profiles - 1``
    node_mass : (ne, nodes) each node's share of its element's mass per unit x3 integral (the
        density times :attr:`smfem.elements.Operators.node_volume`)
    elements : (ne, nodes) the mesh's elements
    T : (3 n_nodes, n_free) the map, at most one entry a row (:func:`smfem.constraints.mode_map`)
    """

    def __init__(self, terms, profile: np.ndarray, node_mass: np.ndarray, elements: np.ndarray,
                 T: sp.spmatrix):
        C, self.keys = terms
        ne, d = C.shape[:2]
        n_profiles, (n_full, n) = int(profile.max()) + 1, T.shape
        T = T.tocoo()
        column, coefficient = np.full(n_full, -1), np.zeros(n_full)
        column[T.row], coefficient[T.row] = T.col, T.data
        dofs = assembly.element_dofs(elements)  # (ne, d)
        rows, cols = column[dofs][:, :, None], column[dofs][:, None, :]
        kept = np.broadcast_to((rows >= 0) & (cols >= 0), (ne, d, d))
        at = lambda a: np.broadcast_to(a, kept.shape)[kept]  # the kept entries of a
        pattern, position = np.unique(at(rows * n + cols), return_inverse=True)
        self.shape, self.indices = (n, n), pattern % n
        self.indptr = np.searchsorted(pattern // n, np.arange(n + 1))
        # each kept element entry, T-weighted, to its place in the pattern of its profile's terms
        weight = at(coefficient[dofs][:, :, None] * coefficient[dofs][:, None, :])
        place = at(profile[:, None, None]) * len(pattern) + position.ravel()
        scatter = sp.csr_matrix((weight, (place, np.flatnonzero(kept))),
                                shape=(n_profiles * len(pattern), ne * d * d))
        reduced = (scatter @ C.reshape(ne * d * d, -1)).reshape(n_profiles, len(pattern), -1)
        #: (n_profiles, n_terms, nnz): the reduced terms of each profile's elements
        self.stiffness = np.ascontiguousarray(reduced.transpose(0, 2, 1))
        masses = np.zeros((n_profiles, 2, n_full))
        for g in range(n_profiles):
            share = np.where((profile == g)[:, None], node_mass, 0.0)
            for a in (0, 1):
                masses[g, a] = assembly.lumped_mass(share, np.eye(2)[[a] * ne], elements,
                                                    n_full // 3)
        squared = sp.csr_matrix((T.data**2, (T.row, T.col)), shape=T.shape)  # T'diag(m)T's diagonal
        #: (n_profiles, 2, n): the reduced lumped mass of each profile's elements, per basis type
        self.mass = (masses.reshape(-1, n_full) @ squared).reshape(n_profiles, 2, n)

    def blocks(self, p: float, integrals: np.ndarray) -> tuple[sp.csr_matrix, np.ndarray]:
        """A mode's reduced stiffness (its exact zeros not stored) and lumped mass diagonal, of
        wavenumber ``p`` and x3 integrals ``integrals`` (n_profiles or 1, 2, 2) per profile."""
        I = np.broadcast_to(integrals, (len(self.stiffness), 2, 2))
        # (profiles, terms)
        coefficients = np.stack([I[:, a, b] * p**k for a, b, k in self.keys], axis=1)
        data = coefficients.ravel() @ self.stiffness.reshape(coefficients.size, -1)
        K = sp.csr_matrix((data, self.indices.copy(), self.indptr.copy()), shape=self.shape)
        if not data.all():
            K.eliminate_zeros()
        return K, np.einsum("ga,gan->n", I[:, [0, 1], [0, 1]], self.mass)
