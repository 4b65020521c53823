"""Mass matrices: consistent, lumped (for explicit time stepping), and redistributed away from
a contact face.

With exact (Lagrange multiplier) contact, the consistent mass gives the contact nodes an
inertia of their own: Newmark then bounces them off the wall every other step, the wall force
chatters and energy is pumped into the body. The mass redistribution of Khenous, Laborde &
Renard (Eur. J. Mech. A/Solids 27, 2008) leaves the contact nodes massless, so their
displacement follows the body quasi-statically and the semi-discrete problem is well posed.
Here the elements with a facet on the contact face integrate their mass with the midpoint rule
across the layer (the reference coordinate normal to that facet) and the usual Gauss rule
along it: the shape functions of the face's nodes vanish at the midpoint, the layer's mass and
centre of mass are kept, and its mass sits on the mid-layer nodes.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from . import ties

#: Gauss points per direction along the layer (as the model's INTORDER = 4 rule)
N_GAUSS = 3


def density(basis, rho: float | np.ndarray) -> float | np.ndarray:
    """The density as a form takes it: a number as it is; one per element of the mesh
    ``(n_mesh_elements,)`` (a body of several materials) at the quadrature points of the elements
    of ``basis``, ``(n_elements, n_qp)``."""
    if np.ndim(rho) == 0:
        return rho
    elements = slice(None) if basis.tind is None else basis.tind
    return np.ascontiguousarray(np.broadcast_to(np.asarray(rho)[elements][:, None], basis.dx.shape))


def scalar_functions(basis) -> tuple[np.ndarray, np.ndarray]:
    """The scalar element's functions at the quadrature points of a vector ``basis``, ``(n_local,
    n_elements, n_qp)``, and their dofs ``(n_local, n_elements)``: the vector element's function
    ``dim j`` is the scalar function ``j`` in component 0, at ``dim`` times its scalar dof (dof
    ``dim * i + c`` is component c at scalar dof i), so no scalar basis is built."""
    dim = basis.mesh.dim()
    phi = np.array([np.asarray(basis.basis[dim * j][0])[0] for j in range(basis.Nbfun // dim)])
    return phi, basis.element_dofs[::dim] // dim


def consistent_mass(basis, rho: float | np.ndarray, axisymmetric: bool, factor: np.ndarray | None = None
                    ) -> sp.csr_matrix:
    """``int rho u . v`` (times r when axisymmetric) over the elements of ``basis``; ``rho`` a
    number or one per element of the mesh (:func:`density`); ``factor`` (n_elements, n_qp): the
    density's variation at the quadrature points."""
    # the scalar element's mass element by element, one copy per component: a vector form would
    # evaluate every pair of the element's vector functions, dim^2 times as many
    phi, dofs = scalar_functions(basis)
    r = np.asarray(basis.global_coordinates())[0] if axisymmetric else 1.0
    w = density(basis, rho) * basis.dx * r * (1.0 if factor is None else factor)  # (n_elements, n_qp)
    phi = phi.transpose(1, 0, 2)  # (n_elements, n_local, n_qp)
    Me = phi @ (phi * w[:, None, :]).transpose(0, 2, 1)  # a product per element, not a 3-way einsum
    rows = np.broadcast_to(dofs.T[:, :, None], Me.shape).ravel()
    cols = np.broadcast_to(dofs.T[:, None, :], Me.shape).ravel()
    n = basis.N // basis.mesh.dim()
    M = sp.csr_matrix((Me.ravel(), (rows, cols)), shape=(n, n))
    return component_copies(M, basis.mesh.dim())


def component_copies(M: sp.csr_matrix, dim: int) -> sp.csr_matrix:
    """``M`` of scalar dofs once per component: ``kron(M, I_dim)`` (dof ``dim i + c`` is component
    ``c`` at scalar dof ``i``), its rows placed at once (scipy's ``kron`` goes through coordinates
    and sorts them again)."""
    counts = np.repeat(np.diff(M.indptr), dim)  # each scalar row's entries, once per component
    indptr = np.r_[0, np.cumsum(counts)]
    # entry k of new row dim i + c is entry k of scalar row i, in column dim j + c
    source = np.arange(indptr[-1]) - np.repeat(indptr[:-1] - np.repeat(M.indptr[:-1], dim), counts)
    component = np.repeat(np.tile(np.arange(dim), M.shape[0]), counts)
    return sp.csr_matrix((M.data[source], dim * M.indices[source] + component, indptr),
                         shape=(dim * M.shape[0], dim * M.shape[1]))


def lumped_mass(basis, rho: float | np.ndarray, axisymmetric: bool,
                factor: np.ndarray | None = None) -> np.ndarray:
    """Diagonal mass by HRZ lumping (Hinton, Rock & Zienkiewicz 1976), shape ``(n_dof,)``.

    Each element's consistent diagonal ``int rho phi_i^2`` is scaled so that it sums to the
    element's mass: every entry is positive for any Lagrange element (nodal quadrature of the
    9-node quadrilateral gives zero to the axis nodes of an axisymmetric section, whose axial
    motion then has no inertia) and the total mass is kept. Same units and ``rho`` as
    :func:`consistent_mass`.
    """
    phi, dofs = scalar_functions(basis)
    r = np.asarray(basis.global_coordinates())[0] if axisymmetric else np.ones(basis.dx.shape)
    w = density(basis, rho) * basis.dx * r * (1.0 if factor is None else factor)  # (n_elements, n_qp)
    diag = np.array([np.einsum("eq,eq->e", p ** 2, w) for p in phi])  # (n_local, nel)
    share = diag * (w.sum(axis=1) / diag.sum(axis=0))
    nodes = np.bincount(dofs.ravel(), share.ravel(), minlength=basis.N // basis.mesh.dim())
    return np.repeat(nodes, basis.mesh.dim())


def redistributed_mass(M: sp.csr_matrix, basis, facets: np.ndarray, rho: float | np.ndarray,
                       axisymmetric: bool, intorder: int) -> sp.csr_matrix:
    """``M`` with the elements on boundary ``facets`` integrated by the layer rule (module doc).

    Parameters
    ----------
    M : consistent mass of ``basis`` (full dofs)
    basis : skfem.CellBasis of the vector quadratic element
    facets : boundary facets of the contact face
    rho : density, a number or one per element of the mesh (:func:`density`)
    intorder : the Gauss order ``M`` was integrated with

    Returns
    -------
    csr_matrix, same total mass and first moments; the face nodes' rows are zero.
    """
    mesh = basis.mesh
    elements = mesh.f2t[0, facets]
    local = np.argmax(mesh.t2f[:, elements] == facets, axis=0)
    # the reference coordinate that is constant on each local facet: the layer's normal direction
    ref = mesh.refdom.p
    normal_dir = np.array([np.flatnonzero(np.ptp(ref[:, f], axis=1) == 0)[0] for f in mesh.refdom.facets])
    out = M.copy()
    for d in np.unique(normal_dir[local]):
        group = elements[normal_dir[local] == d]
        standard = ties.cell_basis(mesh, basis.elem, elements=group, intorder=intorder)
        layer = ties.cell_basis(mesh, basis.elem, elements=group, quadrature=_layer_rule(mesh.dim(), d))
        out = out - consistent_mass(standard, rho, axisymmetric) + consistent_mass(layer, rho, axisymmetric)
    return out.tocsr()


def _layer_rule(dim: int, d: int) -> tuple[np.ndarray, np.ndarray]:
    """Tensor rule on the unit cube: midpoint along direction ``d``, Gauss along the others."""
    x, w = np.polynomial.legendre.leggauss(N_GAUSS)
    axes = [(np.array([0.5]), np.array([1.0])) if k == d else ((x + 1) / 2, w / 2) for k in range(dim)]
    grids = np.meshgrid(*(a[0] for a in axes), indexing="ij")
    weights = np.prod(np.meshgrid(*(a[1] for a in axes), indexing="ij"), axis=0)
    return np.array([g.ravel() for g in grids]), weights.ravel()
