"""Weak forms and the strain operator.

Strains and stresses are Mandel vectors (shear components times sqrt 2, so that
``sigma : eps = sigma_m . eps_m`` and the tangent is a symmetric matrix):

- 2D, 4 components ``(xx, yy, oo, sqrt2 xy)`` in the mesh frame, ``oo`` the out-of-plane
  direction (plane strain: zero strain; axisymmetric: hoop strain ``u_r / r``);
- 3D, 6 components ``(xx, yy, zz, sqrt2 yz, sqrt2 xz, sqrt2 xy)``.

``weights`` are the quadrature weights times ``|det J|`` (times ``r`` when axisymmetric: every
axisymmetric integral is per radian of circumference).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import LinearForm
from skfem.helpers import dot

SQRT2 = np.sqrt(2.0)


def n_components(dim: int) -> int:
    """Number of Mandel components in ``dim`` mesh dimensions."""
    return 4 if dim == 2 else 6


#: elements whose dense strain blocks :func:`stiffness` and :func:`strain_operator` form at once
#: (a 27-node element's are 105 kB: about a hundred MB of work arrays, whatever the mesh; 2000 at
#: once ran slower on a first call, its half-GB of fresh pages)
ELEMENT_CHUNK = 256


def strain_operator(basis, axisymmetric: bool, elements=None) -> sp.csr_matrix:
    """Sparse strain operator ``B``.

    Parameters
    ----------
    basis : skfem.CellBasis of an ``ElementVector`` (2D or 3D)
    axisymmetric : mesh coordinates are (r, z); adds the hoop strain ``u_r / r``
    elements : the elements whose rows to make, in that order (default: every element)

    Returns
    -------
    csr_matrix, shape ``(n_qp * n_comp, n_dof)``; row ``q * n_comp + c`` is Mandel component
    ``c`` at quadrature point ``q = element * n_qp_per_element + k`` (of ``elements``: each
    one's rows the same as in the whole operator)
    """
    nc = n_components(basis.mesh.dim())
    chosen = np.arange(basis.dx.shape[0]) if elements is None else np.atleast_1d(elements)
    nqe = basis.dx.shape[1]
    data, cols, rows = [], [], []
    for start in range(0, chosen.size, ELEMENT_CHUNK):
        chunk = chosen[start:start + ELEMENT_CHUNK]
        Be = element_strains(basis, axisymmetric, chunk)  # (n, nqe, nc, n_local)
        points = start * nqe + np.arange(chunk.size * nqe)
        row = (points[:, None] * nc + np.arange(nc)).reshape(chunk.size, nqe, nc)
        for i in range(basis.Nbfun):
            values = Be[..., i]
            nonzero = values != 0.0  # a vector basis function moves one component only
            data.append(values[nonzero])
            rows.append(row[nonzero])
            cols.append(np.broadcast_to(basis.element_dofs[i][chunk][:, None, None], values.shape)[nonzero])
    return sp.csr_matrix(
        (np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))),
        shape=(chosen.size * nqe * nc, basis.N),
    )


def quadrature_weights(basis, axisymmetric: bool) -> np.ndarray:
    """The integration weights ``(n_qp,)``, quadrature points numbered as the rows of
    :func:`strain_operator`: volume, or per radian (times ``r``) when axisymmetric."""
    radius = np.asarray(basis.global_coordinates())[0] if axisymmetric else 1.0
    return (basis.dx * radius).ravel()


#: the Mandel shear components' index pairs: 2D ``sqrt2 xy``; 3D ``sqrt2 yz, xz, xy``
SHEAR = {2: ((0, 1),), 3: ((1, 2), (0, 2), (0, 1))}


def element_strains(basis, axisymmetric: bool, elements) -> np.ndarray:
    """Mandel strains of every vector function of ``basis`` at the quadrature points of
    ``elements``, ``(n_elements, n_qp, nc, n_local)``: the vector function ``dim j + a`` is the
    scalar function ``j`` along component ``a``, so its strains are the scalar gradient's
    entries placed (normal ``a``; the shears that pair ``a`` with another direction, over sqrt 2;
    axisymmetric: the hoop strain ``phi / r`` of the radial ones)."""
    dim = basis.mesh.dim()
    scalars = [basis.basis[dim * j][0] for j in range(basis.Nbfun // dim)]  # along component 0
    G = np.stack([f.grad[0][:, elements] for f in scalars], axis=-1)  # (dim, n, nqe, n_scalar)
    Be = np.zeros(G.shape[1:3] + (n_components(dim), G.shape[3], dim))
    for k in range(dim):
        Be[:, :, k, :, k] = G[k]
    for c, (k, l) in enumerate(SHEAR[dim], start=n_components(dim) - len(SHEAR[dim])):
        Be[:, :, c, :, k] = G[l] / SQRT2
        Be[:, :, c, :, l] = G[k] / SQRT2
    if axisymmetric:
        radius = np.asarray(basis.global_coordinates())[0][elements]
        Be[:, :, 2, :, 0] = np.stack([np.asarray(f)[0][elements] for f in scalars], axis=-1) / radius[..., None]
    return Be.reshape(Be.shape[:3] + (-1,))


def elastic_matrix(lam: float, mu: float, dim: int) -> np.ndarray:
    """Isotropic elasticity in Mandel form, shape ``(n_comp, n_comp)``: ``lam m m^T + 2 mu I``."""
    nc = n_components(dim)
    m = np.zeros(nc)
    m[:3] = 1.0
    return lam * np.outer(m, m) + 2.0 * mu * np.eye(nc)


def at_points(D: np.ndarray, points) -> np.ndarray:
    """The elastic matrix at ``points`` (an index or an index array): ``D`` itself for one
    material ``(nc, nc)``, its rows of a per-point ``(n_qp, nc, nc)`` (several materials)."""
    return D if D.ndim == 2 else D[points]


def elastic_stress(strain: np.ndarray, D: np.ndarray) -> np.ndarray:
    """``D eps`` at every point, ``(n_qp, nc)``, of strains ``(n_qp, nc)``; ``D`` one matrix
    ``(nc, nc)`` or one per point ``(n_qp, nc, nc)``.

    By einsum, not a BLAS matrix product: threaded BLAS on this tall, thin product stalls on
    a busy machine (15 ms against 2 ms measured, 3D rod)."""
    if D.ndim == 2:
        return np.einsum("qc,cd->qd", strain, D)
    return np.einsum("qc,qcd->qd", strain, D)


def material_blocks(D: np.ndarray, weights: np.ndarray) -> sp.bsr_matrix:
    """Block-diagonal matrix of ``weights[q] * D[q]``; ``D`` is ``(n_qp, nc, nc)`` or ``(nc, nc)``."""
    nq = weights.shape[0]
    D = np.broadcast_to(D, (nq,) + D.shape[-2:]) * weights[:, None, None]
    return sp.bsr_matrix((D, np.arange(nq), np.arange(nq + 1)), shape=(nq * D.shape[1],) * 2)


def stiffness(basis, axisymmetric: bool, weights: np.ndarray, D: np.ndarray,
              projection: np.ndarray | None = None) -> sp.csr_matrix:
    """``K = B^T diag(w D) B`` (N/m, or N/m per radian when axisymmetric), element by element.

    Each element's ``B_e^T (w D) B_e`` is one dense product over its quadrature points, ``B_e``
    the element's strains of :func:`strain_operator` (with the B-bar ``projection`` of
    :func:`volumetric_projection`, as :func:`bbar_operator` applies it); summed into K once
    (the 3D thick cylinder at refine 2: 1.6 CPU s against 3.8 s for the sparse product
    ``B^T (w D B)``, equal to 7e-16 of its largest entry: benchmarks/reference_setup.py).
    Entries that cancel exactly are dropped.
    """
    nel, nqe = basis.dx.shape
    nc = D.shape[-1]
    wD = (np.broadcast_to(D, (weights.size, nc, nc)) * weights[:, None, None]).reshape(nel, nqe, nc, nc)
    parts = []  # each chunk's sum (its duplicates summed: a few times fewer entries than its blocks)
    for start in range(0, nel, ELEMENT_CHUNK):
        chunk = slice(start, min(start + ELEMENT_CHUNK, nel))
        Be = element_strains(basis, axisymmetric, chunk)  # (n, nqe, nc, n_local)
        if projection is not None:
            theta = Be[:, :, :3].sum(axis=2)  # (n, nqe, n_local)
            Be[:, :, :3] += (projection[chunk] @ theta)[:, :, None] / 3.0
        n, n_local = Be.shape[0], Be.shape[-1]
        Ke = Be.reshape(n, nqe * nc, n_local).transpose(0, 2, 1) @ (wD[chunk] @ Be).reshape(n, nqe * nc, n_local)
        dofs = basis.element_dofs[:, chunk].T
        rows = np.broadcast_to(dofs[:, :, None], Ke.shape).ravel()
        cols = np.broadcast_to(dofs[:, None, :], Ke.shape).ravel()
        parts.append(sp.coo_matrix((Ke.ravel(), (rows, cols)), shape=(basis.N, basis.N)).tocsr())
    if len(parts) > 1:
        parts = [part.tocoo() for part in parts]
        K = sp.csr_matrix((np.concatenate([c.data for c in parts]), (np.concatenate([c.row for c in parts]),
                                                                      np.concatenate([c.col for c in parts]))),
                          shape=(basis.N, basis.N))
    else:
        K = parts[0]
    K.eliminate_zeros()
    return K


def internal_forces(B: sp.csr_matrix, weights: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """Nodal internal forces ``B^T (w sigma)`` from Mandel stresses ``sigma``, shape ``(n_qp, nc)``."""
    return B.T @ (sigma * weights[:, None]).ravel()


@LinearForm
def body_force(v, w):
    """A distributed force ``w.b`` (mesh-frame components at the quadrature points of the
    elements, or of boundary facets: a traction), times ``w.weight``."""
    return dot(w.b, v) * w.weight


@LinearForm
def pressure(v, w):
    """Pressure ``w.q`` (compression positive) on the outward normal ``w.n``, times ``w.weight``."""
    return -w.q * dot(w.n, v) * w.weight


def bbar_operator(B: sp.csr_matrix, projection: np.ndarray) -> sp.csr_matrix:
    """The strain operator with its volumetric part projected per element (B-bar, Hughes 1980).

    The volumetric strain ``theta = eps_1 + eps_2 + eps_3`` at an element's quadrature points
    is replaced by its weighted L2 projection onto ``{1, x, y(, z)}`` over the element (the
    pressure space of the Q9/P3 and Q27/P4 mixed elements, stable and free of volumetric
    locking); the deviatoric strain is left alone. In plane strain the out-of-plane normal
    strain then becomes ``(theta_bar - theta) / 3``, as in the 3D form.

    Parameters
    ----------
    B : strain operator of :func:`strain_operator`, rows ``q * nc + c``
    projection : (n_elements, k, k), :func:`volumetric_projection`
    """
    nel, k = projection.shape[:2]
    n_qp = nel * k
    nc = B.shape[0] // n_qp
    # rows summing the three normal components: theta = S B u
    S = sp.csr_matrix((np.ones(3 * n_qp), (np.repeat(np.arange(n_qp), 3), (np.arange(n_qp)[:, None] * nc
                       + np.arange(3)).ravel())), shape=(n_qp, n_qp * nc))
    blocks = sp.bsr_matrix((projection, np.arange(nel), np.arange(nel + 1)), shape=(n_qp, n_qp)).tocsr()
    theta = S @ B
    out = (B + S.T @ (blocks @ theta) / 3.0).tocsr()
    out.data[np.abs(out.data) <= 1e-14 * np.abs(out.data).max()] = 0.0  # the projection's round-off
    out.eliminate_zeros()
    return out


def volumetric_projection(weights: np.ndarray, x_qp: np.ndarray, n_qp_element: int) -> np.ndarray:
    """Per element, the weighted L2 projection onto ``{1, x, y(, z)}`` over its quadrature
    points minus the identity, ``(n_elements, k, k)``: ``theta_bar - theta`` of the volumetric
    strains ``theta`` at the element's ``k`` points (:func:`bbar_operator`)."""
    nel, k = weights.size // n_qp_element, n_qp_element
    x = x_qp.reshape(x_qp.shape[0], nel, k)
    w = weights.reshape(nel, k)
    centre = np.einsum("dek,ek->de", x, w) / w.sum(axis=1)
    phi = np.concatenate([np.ones((1, nel, k)), x - centre[:, :, None]]).transpose(1, 2, 0)  # (nel, k, n_p)
    gram = np.einsum("ekp,ek,ekq->epq", phi, w, phi)
    P = np.einsum("ekp,epq,elq,el->ekl", phi, np.linalg.inv(gram), phi, w)  # (nel, k, k) projections
    return P - np.eye(k)
