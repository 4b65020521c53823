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
from skfem import BilinearForm, LinearForm
from skfem.helpers import dot

SQRT2 = np.sqrt(2.0)


def n_components(dim: int) -> int:
    """Number of Mandel components in ``dim`` mesh dimensions."""
    return 4 if dim == 2 else 6


def strain_operator(basis, axisymmetric: bool) -> tuple[sp.csr_matrix, np.ndarray]:
    """Sparse strain operator ``B`` and the quadrature weights.

    Parameters
    ----------
    basis : skfem.CellBasis of an ``ElementVector`` (2D or 3D)
    axisymmetric : mesh coordinates are (r, z); adds the hoop strain ``u_r / r``

    Returns
    -------
    B : csr_matrix, shape ``(n_qp * n_comp, n_dof)``; row ``q * n_comp + c`` is Mandel
        component ``c`` at quadrature point ``q = element * n_qp_per_element + k``
    weights : ndarray, shape ``(n_qp,)``, integration weights (volume; per radian if
        axisymmetric)
    """
    dim = basis.mesh.dim()
    nc = n_components(dim)
    nel, nqe = basis.dx.shape
    radius = np.asarray(basis.global_coordinates())[0]
    rows = (np.arange(nel * nqe)[:, None] * nc + np.arange(nc)).reshape(nel, nqe, nc)
    data, cols, rr = [], [], []
    for i in range(basis.Nbfun):
        field = basis.basis[i][0]
        g = field.grad  # (dim, dim, nel, nqe): g[a, b] = d u_a / d x_b
        if dim == 2:
            hoop = np.asarray(field)[0] / radius if axisymmetric else np.zeros_like(g[0, 0])
            comps = [g[0, 0], g[1, 1], hoop, (g[0, 1] + g[1, 0]) / SQRT2]
        else:
            comps = [g[0, 0], g[1, 1], g[2, 2], (g[1, 2] + g[2, 1]) / SQRT2,
                     (g[0, 2] + g[2, 0]) / SQRT2, (g[0, 1] + g[1, 0]) / SQRT2]
        values = np.stack(comps, axis=-1)  # (nel, nqe, nc)
        nonzero = values != 0.0  # a vector basis function moves one component only
        data.append(values[nonzero])
        rr.append(rows[nonzero])
        cols.append(np.broadcast_to(basis.element_dofs[i][:, None, None], values.shape)[nonzero])
    B = sp.csr_matrix(
        (np.concatenate(data), (np.concatenate(rr), np.concatenate(cols))),
        shape=(nel * nqe * nc, basis.N),
    )
    weights = (basis.dx * (radius if axisymmetric else 1.0)).ravel()
    return B, weights


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


def stiffness(B: sp.csr_matrix, weights: np.ndarray, D: np.ndarray) -> sp.csr_matrix:
    """``K = B^T diag(w D) B`` (N/m, or N/m per radian when axisymmetric)."""
    return (B.T @ (material_blocks(D, weights) @ B)).tocsr()


def internal_forces(B: sp.csr_matrix, weights: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """Nodal internal forces ``B^T (w sigma)`` from Mandel stresses ``sigma``, shape ``(n_qp, nc)``."""
    return B.T @ (sigma * weights[:, None]).ravel()


@BilinearForm
def scalar_mass(u, v, w):
    """``rho u v`` of scalar functions, times the radius ``w.weight`` when axisymmetric: each
    component's block of the consistent mass ``rho u . v`` (:func:`reference_fem.mass.consistent_mass`)."""
    return w.rho * u * v * w.weight


@LinearForm
def body_force(v, w):
    """A distributed force ``w.b`` (mesh-frame components at the quadrature points of the
    elements, or of boundary facets: a traction), times ``w.weight``."""
    return dot(w.b, v) * w.weight


@LinearForm
def pressure(v, w):
    """Pressure ``w.q`` (compression positive) on the outward normal ``w.n``, times ``w.weight``."""
    return -w.q * dot(w.n, v) * w.weight


def bbar_operator(B: sp.csr_matrix, weights: np.ndarray, x_qp: np.ndarray, n_qp_element: int) -> sp.csr_matrix:
    """The strain operator with its volumetric part projected per element (B-bar, Hughes 1980).

    The volumetric strain ``theta = eps_1 + eps_2 + eps_3`` at an element's quadrature points
    is replaced by its weighted L2 projection onto ``{1, x, y(, z)}`` over the element (the
    pressure space of the Q9/P3 and Q27/P4 mixed elements, stable and free of volumetric
    locking); the deviatoric strain is left alone. In plane strain the out-of-plane normal
    strain then becomes ``(theta_bar - theta) / 3``, as in the 3D form.

    Parameters
    ----------
    B : strain operator of :func:`strain_operator`, rows ``q * nc + c``
    weights : (n_qp,) integration weights
    x_qp : (dim, n_qp) quadrature points, element by element (``n_qp_element`` each)
    """
    n_qp = weights.size
    nc = B.shape[0] // n_qp
    nel, k = n_qp // n_qp_element, n_qp_element
    # rows summing the three normal components: theta = S B u
    S = sp.csr_matrix((np.ones(3 * n_qp), (np.repeat(np.arange(n_qp), 3), (np.arange(n_qp)[:, None] * nc
                       + np.arange(3)).ravel())), shape=(n_qp, n_qp * nc))
    x = x_qp.reshape(x_qp.shape[0], nel, k)
    w = weights.reshape(nel, k)
    centre = np.einsum("dek,ek->de", x, w) / w.sum(axis=1)
    phi = np.concatenate([np.ones((1, nel, k)), x - centre[:, :, None]]).transpose(1, 2, 0)  # (nel, k, n_p)
    gram = np.einsum("ekp,ek,ekq->epq", phi, w, phi)
    P = np.einsum("ekp,epq,elq,el->ekl", phi, np.linalg.inv(gram), phi, w)  # (nel, k, k) projections
    P -= np.eye(k)
    blocks = sp.bsr_matrix((P, np.arange(nel), np.arange(nel + 1)), shape=(n_qp, n_qp)).tocsr()
    theta = S @ B
    out = (B + S.T @ (blocks @ theta) / 3.0).tocsr()
    out.data[np.abs(out.data) <= 1e-14 * np.abs(out.data).max()] = 0.0  # the projection's round-off
    out.eliminate_zeros()
    return out
