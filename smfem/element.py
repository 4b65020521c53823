"""Ring and prismatic 4-node elements of the moment scheme (MSFE), batched over elements:
the default element of :mod:`smfem.elements` (``moment4``).

Strain rows are ``[e11, e22, e33, g12, g13, g23]`` (engineering shears) in the element's local
frame: ``t1`` along the element's first local coordinate at its centre, ``t2`` normal to it in
the section, ``3`` along x3. Nodal dofs are node-major ``[u1, u2, u3]`` per node in the global
section axes, so an element operator has 12 columns.

The operator of one harmonic is ``B(p) = Ba + p Bb``, linear in the wavenumber ``p`` (ring: l;
prism: l pi / length). The moment scheme keeps the centre value ``B0`` and, of the first
derivatives along the local coordinates ``xi, eta`` in [-1/2, 1/2], only the rows that may vary:
``d/dxi``: e22, e33, g23; ``d/deta``: e11, e33, g13. With ``int xi^2 = 1/12`` the element
stiffness is ``sqrt(g) [B0' D B0 + (B1' D B1 + B2' D B2) / 12]`` (paper (3)-(5)).

The normal strain that the scheme does not let vary along a direction (e11 along xi, e22
along eta) is not held at zero but left free, like Wilson's incompatible modes: it takes the
value that makes its own stress gradient vanish, ``e11,1 = -c (e22,1 + e33,1)`` and
``e22,2 = -c (e11,2 + e33,2)`` with ``c = lambda / (lambda + 2 mu) = nu / (1 - nu)``. Held at
zero, it made the volumetric strain gradient a second constraint per element, weighted by
lambda: the element locked as nu -> 1/2 (thick cylinder, nu = 0.4999: 54 % off Lame on the
paper mesh), and thin parts were too stiff in bending (sigma22 could not relax through the
thickness). Left free, the gradient terms carry only moduli that stay bounded as nu -> 1/2;
constant-strain states have no gradients, so the patch test is unaffected, and so is nu = 0.
The derivatives are taken by complex-step differentiation of the exact strain expressions
(1/r terms and the varying Jacobian included), which is exact to round-off and carries the
metric terms h(ii),b of the paper without writing them out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cases.geometry import RING

#: local node signs (s_i, t_i) of N_i = (s_i xi + 1/2)(t_i eta + 1/2), counter-clockwise
NODE_S = np.array([-1.0, 1.0, 1.0, -1.0])
NODE_T = np.array([-1.0, -1.0, 1.0, 1.0])
#: rows that the scheme lets vary along xi (B1) and along eta (B2)
ROWS_VARY_XI = np.array([0, 1, 1, 0, 0, 1], bool)
ROWS_VARY_ETA = np.array([1, 0, 1, 0, 1, 0], bool)
_STEP = 1e-30  # complex step: no subtractive cancellation, so any tiny step is exact
#: the 2 x 2 Gauss points (+-a, +-a), counter-clockwise: the stress sample points. Because
#: a^2 = 1/12, the mean over them of B' D B, B = B0 + xi B1 + eta B2, is the stiffness below
GAUSS_A = 0.5 / np.sqrt(3.0)
GAUSS_XI = GAUSS_A * np.array([-1.0, 1.0, 1.0, -1.0])
GAUSS_ETA = GAUSS_A * np.array([-1.0, -1.0, 1.0, 1.0])


def shape_functions(xi, eta):
    """Bilinear ``N (.., 4)``, ``dN/dxi``, ``dN/deta`` at local coordinates in [-1/2, 1/2]."""
    xi, eta = np.asarray(xi)[..., None], np.asarray(eta)[..., None]
    a, b = NODE_S * xi + 0.5, NODE_T * eta + 0.5
    return a * b, NODE_S * b, a * NODE_T


def gauss_interpolation(xi: float, eta: float) -> np.ndarray:
    """(4,) weights of the values at the Gauss points that interpolate them bilinearly at ``(xi, eta)``."""
    return (1 + GAUSS_XI * xi / GAUSS_A**2) * (1 + GAUSS_ETA * eta / GAUSS_A**2) / 4


def mean_basis() -> np.ndarray:
    """(4, 1) the B-bar projection's functions at the Gauss points: constants, the element mean
    (:mod:`smfem.bbar`)."""
    return np.ones((len(GAUSS_XI), 1))


def at_gauss_points(parts) -> np.ndarray:
    """The moment-scheme strain operator ``B0 + xi B1 + eta B2`` (each (ne, 6, 12)) at the four
    Gauss points: (ne, 4, 6, 12)."""
    B0, B1, B2 = parts
    return B0[:, None] + GAUSS_XI[None, :, None, None] * B1[:, None] + GAUSS_ETA[None, :, None, None] * B2[:, None]


@dataclass(frozen=True)
class ElementOperators:
    """Moment-scheme strain operators of all elements, ``(n_elements, 6, 12)`` each.

    ``B0 = Ba0 + p Bb0`` etc.; ``sqrt_g`` (n_elements,) is |det J| at the centre, times r_c for
    a ring; ``rotation`` (n_elements, 2, 2) has rows t1, t2; ``free_ratio`` is
    ``nu / (1 - nu)``, the factor of the free normal strain gradients (module docstring): one
    number, or (n_elements, 1) on a section of several materials.
    """

    Ba: tuple[np.ndarray, np.ndarray, np.ndarray]
    Bb: tuple[np.ndarray, np.ndarray, np.ndarray]
    sqrt_g: np.ndarray
    rotation: np.ndarray
    free_ratio: float | np.ndarray

    def subset(self, elements: np.ndarray) -> "ElementOperators":
        """The operators of some elements only."""
        return ElementOperators(tuple(a[elements] for a in self.Ba), tuple(b[elements] for b in self.Bb),
                                self.sqrt_g[elements], self.rotation[elements],
                                self.free_ratio if np.ndim(self.free_ratio) == 0 else self.free_ratio[elements])

    def at(self, p: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(B0, B1, B2)`` for wavenumber ``p``: the rows the scheme drops are zero, except the
        free normal strain gradients e11,1 and e22,2."""
        B0, B1, B2 = (a + p * b for a, b in zip(self.Ba, self.Bb))
        B1, B2 = B1 * ROWS_VARY_XI[:, None], B2 * ROWS_VARY_ETA[:, None]
        c = self.free_ratio
        B1[:, 0] = -c * (B1[:, 1] + B1[:, 2])
        B2[:, 1] = -c * (B2[:, 0] + B2[:, 2])
        return B0, B1, B2

    def linear_parts(self) -> tuple[tuple, tuple]:
        """``(A, B)`` with ``at(p) = A + p B`` part by part: :meth:`at` is linear in ``p``, the
        dropped and free rows included."""
        A = self.at(0.0)
        return A, tuple(one - zero for one, zero in zip(self.at(1.0), A))

    # -- smfem.elements.Operators --------------------------------------------------------------
    @property
    def node_volume(self) -> np.ndarray:
        """(n, 4): a quarter of the element to each node (paper (6))."""
        return np.repeat((0.25 * self.sqrt_g)[:, None], 4, axis=1)

    @property
    def sample_weights(self) -> np.ndarray:
        """(n, 4): a quarter of the element to each Gauss point."""
        return self.node_volume

    def strain(self, p: float, xi, eta) -> np.ndarray:
        B0, B1, B2 = self.at(p)
        return B0 + xi * B1 + eta * B2

    def at_samples(self, p: float) -> np.ndarray:
        return at_gauss_points(self.at(p))

    def sample_linear_parts(self) -> tuple[np.ndarray, np.ndarray]:
        return tuple(at_gauss_points(parts) for parts in self.linear_parts())

    def stiffness(self, p: float, D: np.ndarray, q: float | None = None) -> np.ndarray:
        return element_stiffness(self, p, D, q)


def local_frame(X: np.ndarray, shape=shape_functions) -> np.ndarray:
    """(n, 2, 2) rotations with rows t1 (along xi at the centre) and t2 (t1 turned by +90 deg);
    ``shape``: the element's shape functions (any node count)."""
    _, dxi, _ = shape(0.0, 0.0)
    t1 = np.einsum("eia,i->ea", X, dxi)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    return np.stack([t1, np.column_stack([-t1[:, 1], t1[:, 0]])], axis=1)


def strain_rotation(R: np.ndarray) -> np.ndarray:
    """(n, 6, 6) map of strain rows from global section axes to the frame with rows R."""
    c, s = R[:, 0, 0], R[:, 0, 1]
    T = np.zeros((len(R), 6, 6))
    T[:, 0, 0], T[:, 0, 1], T[:, 0, 3] = c * c, s * s, c * s
    T[:, 1, 0], T[:, 1, 1], T[:, 1, 3] = s * s, c * c, -c * s
    T[:, 3, 0], T[:, 3, 1], T[:, 3, 3] = -2 * c * s, 2 * c * s, c * c - s * s
    T[:, 2, 2] = 1.0
    T[:, 4, 4], T[:, 4, 5], T[:, 5, 4], T[:, 5, 5] = c, s, -s, c
    return T


def strain_operator(X: np.ndarray, body: str, p: float, xi, eta, shape=shape_functions) -> np.ndarray:
    """Full strain operator ``(n, 6, 3 nodes)`` in global section axes at one local point of
    the isoparametric element with shape functions ``shape`` (the bilinear one by default).

    ``xi`` and ``eta`` may be complex (complex-step differentiation). Ring: x1 = r and
    e33 = (u1 + p u3) / r, g13 = u3,1 - u3 / r - p u1 / r, g23 = u3,2 - p u2 / r.
    Prism: e33 = -p u3, g13 = p u1 + u3,1, g23 = p u2 + u3,2.
    """
    N, dxi, deta = shape(xi, eta)
    nodes = X.shape[1]
    J = np.stack([np.einsum("eia,i->ea", X, dxi), np.einsum("eia,i->ea", X, deta)], axis=2)
    det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
    inv = np.stack([np.stack([J[:, 1, 1], -J[:, 0, 1]], 1), np.stack([-J[:, 1, 0], J[:, 0, 0]], 1)], 1) / det[:, None, None]
    dN = np.stack([dxi, deta])  # (2, nodes)
    G = np.einsum("bi,eba->eia", dN, inv)  # dN_i / dx_a, (n, nodes, 2)
    n = len(X)
    B = np.zeros((n, 6, nodes, 3), dtype=G.dtype)
    B[:, 0, :, 0] = G[:, :, 0]
    B[:, 1, :, 1] = G[:, :, 1]
    B[:, 3, :, 0], B[:, 3, :, 1] = G[:, :, 1], G[:, :, 0]
    B[:, 4, :, 2], B[:, 5, :, 2] = G[:, :, 0], G[:, :, 1]
    Nn = np.broadcast_to(N, (n, nodes))
    if body == RING:
        r = np.einsum("ei,i->e", X[:, :, 0], N)[:, None]
        on_axis = r == 0
        # on the axis N_i / r takes its limit dN_i / dr (l'Hopital): exact for the fields the
        # axis regularity admits (smfem/constraints.py), whose numerators vanish there
        inv_r = 1.0 / np.where(on_axis, 1.0, r)
        hoop = lambda c: np.where(on_axis, c * G[:, :, 0], c * Nn * inv_r)  # c N_i / r
        B[:, 2, :, 0] = hoop(1.0)
        B[:, 2, :, 2] = hoop(p)
        B[:, 4, :, 2] -= hoop(1.0)
        B[:, 4, :, 0] = hoop(-p)
        B[:, 5, :, 1] = hoop(-p)
    else:
        B[:, 2, :, 2] = -p * Nn
        B[:, 4, :, 0] = p * Nn
        B[:, 5, :, 1] = p * Nn
    return B.reshape(n, 6, 3 * nodes)


def operators(X: np.ndarray, body: str, nu: float) -> ElementOperators:
    """Moment-scheme operators of all elements with nodal coordinates ``X`` (n, 4, 2), for a
    material of Poisson's ratio ``nu`` (it sets the free normal strain gradients)."""
    R = local_frame(X)
    T = strain_rotation(R)
    parts = []
    for p in (0.0, 1.0):
        at = lambda xi, eta: np.einsum("ers,esk->erk", T, strain_operator(X, body, p, xi, eta))
        parts.append((at(0.0, 0.0).real, at(1j * _STEP, 0.0).imag / _STEP, at(0.0, 1j * _STEP).imag / _STEP))
    Ba = parts[0]
    Bb = tuple(b1 - b0 for b1, b0 in zip(parts[1], parts[0]))
    _, dxi, deta = shape_functions(0.0, 0.0)
    J = np.stack([np.einsum("eia,i->ea", X, dxi), np.einsum("eia,i->ea", X, deta)], axis=2)
    sqrt_g = np.abs(np.linalg.det(J))
    if body == RING:
        sqrt_g = sqrt_g * X[:, :, 0].mean(axis=1)
    return ElementOperators(Ba, Bb, sqrt_g, R, nu / (1.0 - nu))


def element_stiffness(ops: ElementOperators, p: float, D: np.ndarray, q: float | None = None) -> np.ndarray:
    """Moment-scheme stiffness blocks ``(n, 12, 12)`` coupling wavenumbers ``p`` (rows) and ``q``.

    ``D`` is ``(n, 6, 6)`` per element, already weighted by the x3 integrals of the basis
    products (see :func:`smfem.assembly.weighted_elasticity`); ``q`` defaults to ``p``.
    """
    L0, L1, L2 = ops.at(p)
    R0, R1, R2 = (L0, L1, L2) if q is None or q == p else ops.at(q)
    Lt = lambda L: L.transpose(0, 2, 1)  # batched products: a three-operand einsum loops unoptimized
    k = Lt(L0) @ D @ R0
    k += (Lt(L1) @ D @ R1 + Lt(L2) @ D @ R2) / 12.0
    return k * ops.sqrt_g[:, None, None]
