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


#: elements whose dense blocks :func:`stiffness` (gradients' or strains' products) and
#: :func:`strain_operator` form at once (a 27-node element's strains are 105 kB: about a hundred
#: MB of work arrays, whatever the mesh; 2000 at once ran slower on a first call, its half-GB of
#: fresh pages)
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


def scalar_gradients(basis, axisymmetric: bool, elements) -> np.ndarray:
    """The scalar element's gradients at the quadrature points of ``elements``, ``(n_elements,
    n_qp, g, n_scalar)``: ``g = dim`` derivatives, axisymmetric also the value over ``r`` (the
    hoop strain of a radial function), read off the vector basis (its function ``dim j`` is the
    scalar function ``j`` along component 0)."""
    dim = basis.mesh.dim()
    scalars = [basis.basis[dim * j][0] for j in range(basis.Nbfun // dim)]
    rows = [np.stack([f.grad[0][k][elements] for f in scalars], axis=-1) for k in range(dim)]
    if axisymmetric:
        radius = np.asarray(basis.global_coordinates())[0][elements]
        values = np.stack([np.asarray(f)[0][elements] for f in scalars], axis=-1)
        rows.append(values / radius[..., None])
    return np.stack(rows, axis=2)


def strain_map(dim: int, axisymmetric: bool) -> np.ndarray:
    """``P`` ``(nc, dim, g)``: Mandel strain ``c`` of a displacement is ``P[c, a, k] E[a, k]``,
    ``E[a, k]`` entry ``k`` of :func:`scalar_gradients` of displacement component ``a`` (normal
    ``a``; the shears pairing ``a`` with another direction, over sqrt 2; the hoop strain
    ``u_r / r``)."""
    nc = n_components(dim)
    P = np.zeros((nc, dim, dim + int(axisymmetric)))
    for k in range(dim):
        P[k, k, k] = 1.0
    for c, (k, l) in enumerate(SHEAR[dim], start=nc - len(SHEAR[dim])):
        P[c, k, l] = P[c, l, k] = 1.0 / SQRT2
    if axisymmetric:
        P[2, 0, dim] = 1.0
    return P


def element_strains(basis, axisymmetric: bool, elements) -> np.ndarray:
    """Mandel strains of every vector function of ``basis`` at the quadrature points of
    ``elements``, ``(n_elements, n_qp, nc, n_local)``: the vector function ``dim j + a`` is the
    scalar function ``j`` along component ``a``, so its strains are :func:`strain_map`'s of the
    scalar's :func:`scalar_gradients` placed in component ``a``."""
    dim = basis.mesh.dim()
    G = scalar_gradients(basis, axisymmetric, elements)  # (n, nqe, g, n_scalar)
    P = strain_map(dim, axisymmetric)
    Be = np.zeros(G.shape[:2] + (P.shape[0], G.shape[3], dim))
    for c, a, k in zip(*np.nonzero(P)):  # a few entries: no product over the zeros
        Be[:, :, c, :, a] += P[c, a, k] * G[:, :, k]
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
    """``K = B^T diag(w D) B`` (N/m, or N/m per radian when axisymmetric), element by element,
    as blocks of node pairs (:class:`NodePairs`); entries that cancel exactly are dropped.

    Where ``D`` is one per element (one material, or regions) each element's blocks are
    ``sum_q w_q G_q^T C G_q`` of its scalar functions' gradients ``G`` (:func:`scalar_gradients`)
    and the elasticity ``C = P^T D P`` (:func:`strain_map`): one product of the gradients over
    the element's points per pair of derivatives (27 x 27 x 9 in 3D), then ``C`` on each pair of
    nodes, where the strains' product ``B_e^T (w D) B_e`` (81 x 81 over 162 rows) spends six
    times the flops on the strains' zeros. With the B-bar ``projection`` of
    :func:`volumetric_projection` (which couples an element's points) or a ``D`` that varies
    within an element, the strains' product (:func:`element_strains`, as :func:`bbar_operator`
    projects them).
    """
    nel, nqe = basis.dx.shape
    dim = basis.mesh.dim()
    pairs = NodePairs(basis)
    by_element = elastic_per_element(D, nel, nqe) if projection is None else None
    if by_element is not None:
        P = strain_map(dim, axisymmetric)
        # C[k, l, a, b]: the elasticity pairing derivative k of component a with derivative l of b
        C = np.einsum("cak,...cd,dbl->...klab", P, by_element, P)
        C = C.reshape(C.shape[:-4] + (-1, dim * dim))
    w = weights.reshape(nel, nqe)
    data = pairs.zeros()
    for start in range(0, nel, ELEMENT_CHUNK):
        chunk = slice(start, min(start + ELEMENT_CHUNK, nel))
        if by_element is not None:
            G = scalar_gradients(basis, axisymmetric, chunk)  # (n, nqe, g, n_scalar)
            n, g, ns = G.shape[0], G.shape[2], G.shape[3]
            weighted = (G * w[chunk, :, None, None]).reshape(n, nqe, g * ns)
            S = G.transpose(0, 2, 3, 1).reshape(n, g * ns, nqe) @ weighted  # (n, (k, i), (l, j))
            S = S.reshape(n, g, ns, g, ns).transpose(0, 2, 4, 1, 3).reshape(n, ns * ns, g * g)
            blocks = S @ (C if C.ndim == 2 else C[chunk])  # (n, node pairs, dim * dim)
        else:
            blocks = _strain_blocks(basis, axisymmetric, w[chunk], D, projection, chunk)
        pairs.add(data, chunk, blocks)
    return pairs.matrix(data)


def _strain_blocks(basis, axisymmetric, w, D, projection, chunk) -> np.ndarray:
    """The blocks of :func:`stiffness` of the elements ``chunk`` by the strains' product,
    ``(n, node pairs, dim * dim)``."""
    n, nqe = w.shape
    dim = basis.mesh.dim()
    nc = D.shape[-1]
    points = np.arange(chunk.start * nqe, chunk.stop * nqe)
    wD = np.broadcast_to(at_points(D, points), (points.size, nc, nc)) * w.reshape(-1, 1, 1)
    wD = wD.reshape(n, nqe, nc, nc)
    Be = element_strains(basis, axisymmetric, chunk)  # (n, nqe, nc, n_local)
    if projection is not None:
        theta = Be[:, :, :3].sum(axis=2)  # (n, nqe, n_local)
        Be[:, :, :3] += (projection[chunk] @ theta)[:, :, None] / 3.0
    n_local = Be.shape[-1]
    rows = Be.reshape(n, nqe * nc, n_local)
    Ke = rows.transpose(0, 2, 1) @ (wD @ Be).reshape(n, nqe * nc, n_local)
    ns = n_local // dim
    return Ke.reshape(n, ns, dim, ns, dim).transpose(0, 1, 3, 2, 4).reshape(n, ns * ns, dim * dim)


def elastic_per_element(D: np.ndarray, nel: int, nqe: int) -> np.ndarray | None:
    """``D`` one matrix ``(nc, nc)`` as it is, one per point ``(n_qp, nc, nc)`` as one per element
    ``(nel, nc, nc)``, or None where it varies within an element."""
    if D.ndim == 2:
        return D
    D = D.reshape(nel, nqe, *D.shape[1:])
    return D[:, 0] if np.array_equal(D, np.broadcast_to(D[:, :1], D.shape)) else None


class NodePairs:
    """The sparse pattern of a vector basis's node pairs: the ``dim x dim`` blocks of a matrix
    whose element ``e`` couples its nodes ``i`` and ``j`` (the vector function ``dim j + a`` is
    node ``j``'s component ``a``, dof ``dim node + a``).

    Each element's ``n_scalar^2`` pairs go to their block by one sparse product (the pairs sorted
    once), so a chunk of elements adds its blocks without a sparse matrix of its own, and the
    matrix is made once from the summed blocks (scipy's block matrix to CSR).
    """

    def __init__(self, basis):
        self.dim = dim = basis.mesh.dim()
        self.n_nodes, self.N = basis.N // dim, basis.N
        nodes = (basis.element_dofs[::dim] // dim).T.astype(np.int64)  # (n_elements, n_scalar)
        self.pairs_per_element = nodes.shape[1] ** 2
        keys, block = np.unique((nodes[:, :, None] * self.n_nodes + nodes[:, None, :]).ravel(),
                                return_inverse=True)
        #: (n_blocks, n_elements * n_scalar^2): the block of each element's pair, one entry a column
        self.gather = sp.csc_matrix((np.ones(block.size), block.ravel(), np.arange(block.size + 1)),
                                    shape=(keys.size, block.size))
        rows = keys // self.n_nodes
        self.indices = keys - rows * self.n_nodes
        self.indptr = np.searchsorted(rows, np.arange(self.n_nodes + 1))

    def zeros(self) -> np.ndarray:
        return np.zeros((self.indices.size, self.dim * self.dim))

    def add(self, data: np.ndarray, elements: slice, blocks: np.ndarray) -> None:
        """Add the ``elements``' blocks ``(n, n_scalar^2, dim * dim)`` to ``data``
        (:meth:`zeros`)."""
        per = self.pairs_per_element
        columns = slice(elements.start * per, elements.stop * per)
        data += self.gather[:, columns] @ blocks.reshape(-1, self.dim * self.dim)

    def matrix(self, data: np.ndarray) -> sp.csr_matrix:
        """The CSR matrix of the summed blocks ``data``, without its exact zeros."""
        out = sp.bsr_matrix((data.reshape(-1, self.dim, self.dim), self.indices, self.indptr),
                            shape=(self.N, self.N)).tocsr()
        out.eliminate_zeros()
        return out


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
