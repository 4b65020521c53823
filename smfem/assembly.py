"""Global sparse assembly of element blocks for one mode pair, the element matrices that every
mode pair's blocks combine, and lumped mass."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .elements import DOFS_PER_NODE
from .fourier import ROW_TYPE


def node_dofs(nodes: np.ndarray) -> np.ndarray:
    """(*nodes.shape, 3) global dofs of nodes: ``3 node + component``."""
    return DOFS_PER_NODE * nodes[..., None] + np.arange(DOFS_PER_NODE)


def element_dofs(elements: np.ndarray) -> np.ndarray:
    """(n_elements, dofs per element) global dofs, node-major."""
    return node_dofs(elements).reshape(len(elements), -1)


def weighted_elasticity(D: np.ndarray, integrals: np.ndarray) -> np.ndarray:
    """Elasticity weighted by the x3 integrals of basis products, per element.

    Parameters
    ----------
    D : (6, 6) or (n, 6, 6) elasticity matrix
    integrals : (n, 2, 2) ``int f psi_a^(l) psi_b^(m) dx3`` for row types a, b (0: psi1, 1: psi3)
        with the element's material factor f(x3)

    Returns
    -------
    (n, 6, 6) array ``D[i, j] * integrals[type(i), type(j)]``.
    """
    W = integrals[:, ROW_TYPE][:, :, ROW_TYPE]
    return D * W


def element_terms(ops, D: np.ndarray) -> tuple[np.ndarray, list[tuple[int, int, int, int]]]:
    """The element matrices every stiffness block combines: with ``B(p) = Ba + p Bb`` at the
    element's sample points (which integrate its stiffness exactly, :mod:`smfem.elements`) and
    the x3 integrals ``I_ab`` of the basis types' products (:func:`weighted_elasticity`), the
    block coupling wavenumbers ``p`` (rows) and ``q`` is ``sum_n I_ab p^u q^v C_n``.

    Parameters
    ----------
    ops : the element's operators on ``ne`` elements (:class:`smfem.elements.Operators`)
    D : (6, 6) or (ne, 6, 6) elasticity matrix

    Returns
    -------
    ``C`` (ne, n_terms, d, d) and each term's ``(a, b, u, v)``; the pairs of basis types whose
    part of ``D`` is zero are left out.
    """
    Ba, Bb = ops.sample_linear_parts()  # (ne, ng, 6, d)
    C, terms = [], []
    for a in (0, 1):
        for b in (0, 1):
            Dab = D * np.outer(ROW_TYPE == a, ROW_TYPE == b)
            if not Dab.any():
                continue
            per_element = "e" * (Dab.ndim - 2)
            for u, v in ((0, 0), (1, 0), (0, 1), (1, 1)):
                left, right = (Ba, Bb)[u], (Ba, Bb)[v]
                C.append(np.einsum(f"eg,egri,{per_element}rs,egsj->eij", ops.sample_weights, left, Dab, right,
                                   optimize=True))
                terms.append((a, b, u, v))
    return np.stack(C, axis=1), terms


def assemble(blocks: np.ndarray, elements: np.ndarray, n_nodes: int) -> sp.csr_matrix:
    """Sum element blocks (n, d, d) into a (3 n_nodes, 3 n_nodes) CSR matrix."""
    dofs = element_dofs(elements)
    d = dofs.shape[1]
    rows = np.repeat(dofs, d, axis=1).ravel()
    cols = np.tile(dofs, (1, d)).ravel()
    n = DOFS_PER_NODE * n_nodes
    return sp.csr_matrix((blocks.ravel(), (rows, cols)), shape=(n, n))


def lumped_mass(node_volume: np.ndarray, rho_integrals: np.ndarray, elements: np.ndarray, n_nodes: int) -> np.ndarray:
    """Diagonal of the lumped mass (paper (6)): each node's share ``node_volume`` (n, nodes) of
    its element's mass (the moment scheme: a quarter).

    ``rho_integrals`` (n, 2) holds ``int rho psi1^2`` and ``int rho psi3^2`` per element; the
    in-plane components take the first, the x3 component the second. Returns (3 n_nodes,).
    """
    per_node = node_volume[:, :, None] * rho_integrals[:, None, [0, 0, 1]]  # (n, nodes, 3)
    m = np.zeros((n_nodes, DOFS_PER_NODE))
    np.add.at(m, elements, per_node)
    return m.ravel()
