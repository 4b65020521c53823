"""B-bar for any section element: the volumetric strain of each harmonic replaced by its
projection per element (Hughes 1980; mean dilatation where the projection is onto constants).

In plastic flow the deviatoric stress is bounded and the volume change is elastic, weighted by
the bulk modulus: each independent volumetric strain an element holds becomes a near constraint,
and a standard element holds more of them than its degrees of freedom can meet (the
moment-scheme quadrilateral three per harmonic: its centre value and its two gradients; the
9-node one nine, one per Gauss point): the element locks. B-bar keeps fewer. The operator at a
sample point is ``B_bar = B + m (theta_bar - theta) / 3``, ``theta = m' B`` (``m`` sums the
three normal strain rows, in any frame: the trace does not depend on it), ``theta_bar`` the
projection of ``theta`` over the element's sample points, weighted as the element integrates
(its ``sample_weights``: the section's volume element, r dA on a ring), onto the element's
:attr:`smfem.elements.Element.bbar_basis`:

* the moment-scheme quadrilateral (:mod:`smfem.element`), constants: the element mean, one
  volumetric strain per element and harmonic (its stiffness is the mean over its four Gauss
  points, so the mean is the centre value ``B0``'s and B-bar drops the gradients' volumetric
  part). Its free normal strain gradients keep their ratio ``nu / (1 - nu)``: the ratio that
  minimizes the gradient energy under B-bar, -1/2, makes the gradient ``e11 = e22 = e33`` purely
  volumetric, which B-bar then leaves without energy: two spurious zero-energy modes per element
  at every harmonic but 0 and 1 (measured on one element).
* the 9-node quadrilateral (:mod:`smfem.quad9`), ``{1, xi, eta}``: the pressure space of the
  stable Q9/P3 element. With constants only, the dilatation ``theta = z - z_c`` of
  ``u_r = r (z - z_c), u_z = ((z - z_c)^2 - r^2) / 2``, which the biquadratic element holds
  exactly, loses its energy: a zero-energy mode of every axisymmetric element, and of a whole
  row of them that shares its z range.

The strain of harmonic ``p`` stays linear in ``p`` and each harmonic keeps its own x3 profile,
so everything past the element (the stiffness per harmonic, the harmonic coupling, the x3 sample
points, the plastic loads) reads ``B_bar`` through the same operators and stays consistent: the
stiffness is the sample-point sum of ``B_bar' D B_bar`` (:mod:`smfem.elements`), and the forces
of an elastic state are ``K u`` as before. The option :attr:`smfem.options.SolverOptions.bbar`;
without it nothing here runs.
"""

from __future__ import annotations

import numpy as np


def projection(basis: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """(ne, ng, ng) weighted L2 projections onto the columns of ``basis`` (ng, n_p): row ``g``
    of an element's matrix gives the projected value at sample point ``g`` of the values at all."""
    gram = np.einsum("gp,eg,gq->epq", basis, weights, basis)
    return np.einsum("gp,epq,hq,eh->egh", basis, np.linalg.inv(gram), basis, weights)


class Projected:
    """An element's operators (:class:`smfem.elements.Operators`) with the volumetric strain
    projected (module docstring).

    Parameters
    ----------
    ops : the element's own operators
    basis : (ng, n_p) the projection's functions at the sample points
    interpolation : ``(xi, eta) -> (ng,)`` the element's interpolation of sample-point values
        to a local point (:attr:`smfem.elements.Element.sample_interpolation`): exact on the
        projection's functions, which lie in the space it interpolates
    """

    def __init__(self, ops, basis: np.ndarray, interpolation):
        self.ops, self.basis, self.interpolation = ops, basis, interpolation
        self.P = projection(basis, ops.sample_weights)

    @property
    def rotation(self) -> np.ndarray:
        return self.ops.rotation

    @property
    def node_volume(self) -> np.ndarray:
        return self.ops.node_volume

    @property
    def sample_weights(self) -> np.ndarray:
        return self.ops.sample_weights

    def subset(self, elements) -> "Projected":
        return Projected(self.ops.subset(elements), self.basis, self.interpolation)

    @staticmethod
    def _volumetric(B: np.ndarray) -> np.ndarray:
        return B[..., 0, :] + B[..., 1, :] + B[..., 2, :]

    def _projected(self, B: np.ndarray) -> np.ndarray:
        """``theta_bar`` (ne, ng, d) of sample-point operators ``B`` (ne, ng, 6, d)."""
        return self.P @ self._volumetric(B)

    def _replaced(self, B: np.ndarray, theta_bar: np.ndarray) -> np.ndarray:
        """``B`` (..., 6, d) with its volumetric strain replaced by ``theta_bar`` (..., d)."""
        out = B.copy()
        out[..., :3, :] += ((theta_bar - self._volumetric(B)) / 3.0)[..., None, :]
        return out

    def _bar(self, B: np.ndarray) -> np.ndarray:
        return self._replaced(B, self._projected(B))

    def at_samples(self, p: float) -> np.ndarray:
        return self._bar(self.ops.at_samples(p))

    def sample_linear_parts(self) -> tuple[np.ndarray, np.ndarray]:
        return tuple(self._bar(part) for part in self.ops.sample_linear_parts())  # the map is linear

    def strain(self, p: float, xi, eta) -> np.ndarray:
        theta_bar = np.einsum("g,egd->ed", self.interpolation(xi, eta), self._projected(self.ops.at_samples(p)))
        return self._replaced(self.ops.strain(p, xi, eta), theta_bar)

    def stiffness(self, p: float, D: np.ndarray, q: float | None = None) -> np.ndarray:
        L = self.at_samples(p)
        R = L if q is None or q == p else self.at_samples(q)
        return np.einsum(f"eg,egri,{'e' * (D.ndim - 2)}rs,egsj->eij", self.sample_weights, L, D, R, optimize=True)


def operators(element, ops) -> Projected:
    """The B-bar operators of ``element`` (:class:`smfem.elements.Element`) from its ``ops``;
    an element without a projection basis is refused."""
    if element.bbar_basis is None:
        raise ValueError(f"element {element.name!r} has no B-bar projection (Element.bbar_basis): set bbar=false")
    return Projected(ops, np.asarray(element.bbar_basis(), float), element.sample_interpolation)
