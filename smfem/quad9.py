"""The 9-node Lagrange quadrilateral (``quad9``), ring and prism, fully integrated by 3 x 3 Gauss
points, batched over elements.

Why 9 nodes rather than the 8-node serendipity element: the Lagrange element keeps its full
biquadratic space under any bilinear (non-affine) map of the section, where the serendipity
element loses completeness and accuracy on distorted meshes; its lumped masses (the
nodal rule, 1/36, 4/36, 16/36 of a parallelogram: :attr:`Quad9Operators.node_volume`) are none negative,
where the serendipity element's corners get negative ones; and its nodes are the tensor-product grid of the section
refined once in (s, t) (:func:`cases.section_mesh.section_mesh` with ``order=2``), so supports, edges and
curved boundaries come for free.

Why full 3 x 3 integration: 2 x 2 reduced integration of the Lagrange element has spurious
zero-energy modes; fully integrated, a quadratic element represents pure bending exactly (its
displacements are quadratic) and locks far less than the bilinear one in thin parts (measured in
``tests/test_quad_element.py``: the clamped plate and the thin dome). Its stiffness *is* the
Gauss sum, so the sample points integrate it exactly, as :mod:`smfem.elements` requires.

Strain rows and the element frame are those of :mod:`smfem.element` (:func:`strain_operator`
and :func:`local_frame` with these shape functions).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from cases.geometry import RING

from .element import local_frame, strain_operator, strain_rotation

#: local node positions (index 0, 1, 2 = -1/2, 0, 1/2 along xi and eta): corners
#: counter-clockwise, then the mid-sides of edges 0-1, 1-2, 2-3, 3-0, then the centre
NODE_I = np.array([0, 2, 2, 0, 1, 2, 1, 0, 1])
NODE_J = np.array([0, 0, 2, 2, 0, 1, 2, 1, 1])
#: 3-point Gauss-Legendre rule on [-1/2, 1/2] (weights sum to 1)
GAUSS_1D = 0.5 * np.sqrt(0.6) * np.array([-1.0, 0.0, 1.0])
WEIGHTS_1D = np.array([5.0, 8.0, 5.0]) / 18.0
#: the 3 x 3 Gauss points, the stress sample points, and the share of the element each weighs
GAUSS_XI, GAUSS_ETA = (a.ravel() for a in np.meshgrid(GAUSS_1D, GAUSS_1D, indexing="ij"))
GAUSS_WEIGHTS = np.outer(WEIGHTS_1D, WEIGHTS_1D).ravel()
#: the nodal (3-point Gauss-Lobatto, Simpson) rule's weight of each node, in the nodes' order
LOBATTO_WEIGHTS = (np.array([1.0, 4.0, 1.0]) / 6.0)[NODE_I] * (np.array([1.0, 4.0, 1.0]) / 6.0)[NODE_J]


def lagrange_1d(s):
    """Quadratic Lagrange functions at -1/2, 0, 1/2 and their derivatives: two (..., 3)."""
    t = 2 * np.asarray(s, dtype=np.result_type(s, float))[..., None]
    L = np.concatenate([t * (t - 1) / 2, 1 - t * t, t * (t + 1) / 2], axis=-1)
    dL = np.concatenate([2 * t - 1, -4 * t, 2 * t + 1], axis=-1)  # d/ds = 2 d/dt
    return L, dL


def shape_functions(xi, eta):
    """Biquadratic ``N (.., 9)``, ``dN/dxi``, ``dN/deta`` at local coordinates in [-1/2, 1/2]."""
    (a, da), (b, db) = lagrange_1d(xi), lagrange_1d(eta)
    a, da, b, db = a[..., NODE_I], da[..., NODE_I], b[..., NODE_J], db[..., NODE_J]
    return a * b, da * b, a * db


def gauss_interpolation(xi: float, eta: float) -> np.ndarray:
    """(9,) weights of the values at the Gauss points that interpolate them biquadratically."""
    g = GAUSS_1D[2]

    def through_points(s):
        return np.array([s * (s - g) / (2 * g * g), 1 - s * s / (g * g), s * (s + g) / (2 * g * g)])

    return np.outer(through_points(xi), through_points(eta)).ravel()


def linear_basis() -> np.ndarray:
    """(9, 3) the B-bar projection's functions ``1, xi, eta`` at the Gauss points (the Q9/P3
    pressure space; :mod:`smfem.bbar` says why not constants)."""
    return np.column_stack([np.ones_like(GAUSS_XI), GAUSS_XI, GAUSS_ETA])


@dataclass(frozen=True, eq=False)
class Quad9Operators:
    """The operators of :mod:`smfem.elements` for nodal coordinates ``X`` (ne, 9, 2)."""

    X: np.ndarray
    body: str

    @cached_property
    def rotation(self) -> np.ndarray:
        return local_frame(self.X, shape_functions)

    @cached_property
    def _to_frame(self) -> np.ndarray:
        return strain_rotation(self.rotation)

    @cached_property
    def sample_weights(self) -> np.ndarray:
        """(ne, 9): |det J| times the Gauss weight (a ring's times r)."""
        N, dxi, deta = shape_functions(GAUSS_XI, GAUSS_ETA)  # (9 points, 9 nodes)
        J = np.stack([np.einsum("gi,eia->ega", dxi, self.X), np.einsum("gi,eia->ega", deta, self.X)], axis=3)
        w = np.abs(np.linalg.det(J)) * GAUSS_WEIGHTS
        return w * np.einsum("gi,ei->eg", N, self.X[:, :, 0]) if self.body == RING else w

    @cached_property
    def node_volume(self) -> np.ndarray:
        """(ne, 9): each node's share of its element's volume, by the element's own nodal rule
        (the 3 x 3 Gauss-Lobatto points are its nodes: weights 1/6, 4/6, 1/6 per direction)
        of the volume ``|det J| r``, scaled to the element's volume.

        On a parallelogram with r linear across it these are the row sums ``int N_i dV``
        (exactly: the rule integrates cubics), 1:4:16 per 36 of a prism. Not the row sums
        themselves: a node on the axis has ``int N_i r dV = 0`` (r vanishes there and is linear
        along the element), which round-off leaves of either sign, and an element that widens
        away from the axis truly negative (``-2 b / 15`` per unit r of a Jacobian
        ``a + b xi``). A negative mass is an unstable mode that Newmark's average acceleration
        amplifies more per unit time the smaller the step (a gmsh rod: -8e-7 kg on its axis
        nodes; its impact blew up at dt 5e-7 s and not at 1e-6). The nodal rule gives every
        node ``w_i |det J_i| r_i >= 0``: the axis nodes none, exactly (their axial motion has no
        inertia, as a face's next to the contact layer). HRZ (the diagonal ``int N_i^2 dV``
        scaled) is positive too, but not a consistent rule of a ring's r-weighted volume: it cut
        the order of a manufactured motion on a distorted ring section from 3 to 2.2.
        """
        X = self.X
        _, dxi, deta = shape_functions(0.5 * (NODE_I - 1), 0.5 * (NODE_J - 1))  # at the nodes: (9, 9)
        J = np.stack([np.einsum("gi,eia->ega", dxi, X), np.einsum("gi,eia->ega", deta, X)], axis=3)
        share = np.abs(np.linalg.det(J)) * LOBATTO_WEIGHTS
        if self.body == RING:
            share = share * np.maximum(X[:, :, 0], 0.0)
        volume = self.sample_weights.sum(axis=1)
        total = share.sum(axis=1)
        return share * np.divide(volume, total, out=np.zeros_like(total), where=total > 0)[:, None]

    def subset(self, elements) -> "Quad9Operators":
        return Quad9Operators(self.X[elements], self.body)

    def strain(self, p: float, xi, eta) -> np.ndarray:
        return np.einsum("ers,esk->erk", self._to_frame, strain_operator(self.X, self.body, p, xi, eta, shape_functions))

    @cached_property
    def _parts(self) -> tuple[np.ndarray, np.ndarray]:
        """``(A, B)`` at the Gauss points: the strain is ``A + p B``, exactly (linear in p)."""
        at = lambda p: np.stack([self.strain(p, a, b) for a, b in zip(GAUSS_XI, GAUSS_ETA)], axis=1)
        A = at(0.0)
        return A, at(1.0) - A

    def at_samples(self, p: float) -> np.ndarray:
        A, B = self._parts
        return A + p * B

    def sample_linear_parts(self) -> tuple[np.ndarray, np.ndarray]:
        return self._parts

    def stiffness(self, p: float, D: np.ndarray, q: float | None = None) -> np.ndarray:
        L = self.at_samples(p)
        R = L if q is None or q == p else self.at_samples(q)
        return np.einsum("eg,egri,ers,egsj->eij", self.sample_weights, L, D, R, optimize=True)


def operators(X: np.ndarray, body: str, nu: float) -> Quad9Operators:
    """The element's operators; ``nu`` is not needed (full integration has no free strains)."""
    return Quad9Operators(np.asarray(X, float), body)
