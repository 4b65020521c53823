"""The element extension point: what SMFEM needs of a section element, and the table of elements.

An element is a record of functions (:class:`Element`); on a mesh it gives its linear
:class:`Operators`, batched over all elements. Everything past the element (assembly, the
stress sample points, the harmonic coupling, Woodbury, fields, probes) reads only these, so
an element is added by one module that implements them and one line in :data:`ELEMENTS`
(or :func:`register`, for one defined elsewhere, as the tests' fully integrated bilinear).

Conventions every element keeps:

* dofs are node-major ``[u1, u2, u3]`` per node in the global section axes
  (:data:`DOFS_PER_NODE`), so an element has ``3 nodes`` of them;
* strain rows are ``[e11, e22, e33, g12, g13, g23]`` (engineering shears) in the element's frame
  (``rotation``: rows t1, t2 in the section, then x3), as :data:`smfem.fourier.ROW_TYPE` types them;
* the strain of harmonic ``p`` (ring: l; prism: l pi / length) is linear in ``p``;
* the stress sample points integrate the stiffness exactly:
  ``stiffness(p, D, q) = sum_g sample_weights_g B_g(p)' D B_g(q)`` with ``B_g = at_samples``.
  The plastic iterations rely on it (the forces of an elastic state are then exactly ``K u``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Protocol

import numpy as np

from . import element, quad9

#: displacement components per node: two in the section, one along x3
DOFS_PER_NODE = 3


class Operators(Protocol):
    """An element's operators on all ``ne`` elements of a mesh (``d`` dofs, ``ng`` sample points).

    Attributes
    ----------
    rotation : (ne, 2, 2) rows t1, t2 of each element's frame, in the section's axes
    node_volume : (ne, nodes) each node's share of its element's volume (a ring's times r): the
        lumped mass per unit density, before the x3 integrals
    sample_weights : (ne, ng) the volume each stress sample point stands for
    """

    rotation: np.ndarray
    node_volume: np.ndarray
    sample_weights: np.ndarray

    def subset(self, elements: np.ndarray) -> "Operators":
        """The operators of some elements only."""

    def strain(self, p: float, xi, eta) -> np.ndarray:
        """Strain operator (ne, 6, d) at one local point ``(xi, eta)`` in [-1/2, 1/2]."""

    def at_samples(self, p: float) -> np.ndarray:
        """Strain operator at the sample points, (ne, ng, 6, d)."""

    def sample_linear_parts(self) -> tuple[np.ndarray, np.ndarray]:
        """``(A, B)`` (ne, ng, 6, d) each, with ``at_samples(p) = A + p B``."""

    def stiffness(self, p: float, D: np.ndarray, q: float | None = None) -> np.ndarray:
        """Stiffness blocks (ne, d, d) coupling wavenumbers ``p`` (rows) and ``q`` (default ``p``),
        of ``D`` (ne, 6, 6) already weighted by the x3 integrals of the basis products."""


@dataclass(frozen=True, eq=False)
class Element:
    """A section element.

    Attributes
    ----------
    name : the key of :data:`ELEMENTS` (``SolverOptions.element``)
    nodes : nodes per element (the section mesh's element width)
    shape_functions : ``(xi, eta) -> (N, dN/dxi, dN/deta)``, each (..., nodes), local
        coordinates in [-1/2, 1/2]: the geometry and the displacement interpolation
    operators : ``(X (ne, nodes, 2), body, nu) -> Operators``
    sample_interpolation : ``(xi, eta) -> (ng,)`` weights that interpolate values at the
        sample points to a local point (the plastic strain probes)
    mesh_order : the section mesh it needs (:func:`cases.section_mesh.section_mesh`): 1, the 4 corners;
        2, the 9 nodes of the mesh refined once in (s, t)
    bbar_basis : ``() -> (ng, n_p)`` the functions, at the sample points, onto which B-bar
        projects the volumetric strain (:mod:`smfem.bbar`); None: the element has no B-bar
    """

    name: str
    nodes: int
    shape_functions: Callable
    operators: Callable[..., Operators]
    sample_interpolation: Callable
    mesh_order: int = 1
    bbar_basis: Callable | None = None

    @property
    def dofs(self) -> int:
        return DOFS_PER_NODE * self.nodes


#: the moment-scheme quadrilateral of the paper (:mod:`smfem.element`), the default
MOMENT4 = Element("moment4", 4, element.shape_functions, element.operators, element.gauss_interpolation,
                  bbar_basis=element.mean_basis)

def _held_gradients(X, body, nu):
    return replace(element.operators(X, body, nu), free_ratio=0.0)


#: the moment scheme with the free normal strain gradients held at zero: the element before the
#: fix in :mod:`smfem.element`, which locks as nu -> 1/2 (the stability study's comparison row)
MOMENT4_HELD = Element("moment4-held-gradients", 4, element.shape_functions, _held_gradients,
                       element.gauss_interpolation, bbar_basis=element.mean_basis)

#: the 9-node Lagrange quadrilateral, fully integrated (:mod:`smfem.quad9`)
QUAD9 = Element("quad9", 9, quad9.shape_functions, quad9.operators, quad9.gauss_interpolation, mesh_order=2,
                bbar_basis=quad9.linear_basis)

#: every element by name
ELEMENTS: dict[str, Element] = {e.name: e for e in (MOMENT4, MOMENT4_HELD, QUAD9)}


def register(new: Element) -> Element:
    """Add an element defined outside this module to :data:`ELEMENTS`."""
    ELEMENTS[new.name] = new
    return new


def get(name: str) -> Element:
    if name not in ELEMENTS:
        raise ValueError(f"element={name!r}: one of {', '.join(map(repr, ELEMENTS))}")
    return ELEMENTS[name]
