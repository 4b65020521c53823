"""The contact layer's law, point by point (paper (17)-(19)): pure functions of arrays shaped
``(n_points, n_x3, ...)``, the layer's points along the face times its points along x3.

A point is open (the layer would carry normal tension: no stress), sticking (normal stiffness
``E_l``, tangential ``G_l``) or slipping (the tangential stress ``f |sigma_n|`` along the slip
direction, Coulomb's law (18)-(19)); :mod:`smfem.contact` builds the layer's elements and steps
on it, :mod:`smfem.layer_descent` is the step that always settles.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .newmark import StepFailed

OPEN, STICK, SLIP = 0, 1, 2
NORMAL = 1  # strain row e22: normal to the layer
SHEAR = [3, 5]  # g12 (tangential in the section plane) and g23 (tangential along x3)
TRACTION = [NORMAL] + SHEAR  # the only rows that carry stress in the layer
#: a layer point closed by less than this strain (1e-14 m across a 0.1 mm layer) is open: where
#: two faces just touch at the end of a step, round-off would otherwise flip their points
#: between open and closed for ever
CLOSURE_TOL = 1e-10
#: a slip direction that moves less than this between iterations has settled
DIRECTION_TOL = 1e-6


class LayerStates(NamedTuple):
    """State of every layer point, ``(n_points, n_x3)`` arrays.

    ``kind``: OPEN, STICK or SLIP; ``direction`` (.., 2): unit slip direction in the two
    tangential shears (zero unless slipping); ``kappa``: ``f |sigma_n| / |tau_trial|`` of a
    slipping point, the weight of the slip direction's change in the consistent tangent.
    """

    kind: np.ndarray
    direction: np.ndarray
    kappa: np.ndarray

    def close_to(self, other: LayerStates, tol: float = DIRECTION_TOL) -> bool:
        """Same kinds and slip directions within ``tol``: an iteration has come back here."""
        return np.array_equal(self.kind, other.kind) and np.abs(self.direction - other.direction).max(initial=0.0) < tol

    def key(self) -> bytes:
        return self.kind.tobytes() + self.direction.tobytes() + self.kappa.tobytes()


# -- the layer's law, point by point: pure functions of arrays (n_points, n_x3, ...) ----------
def layer_states(strain: np.ndarray, pre_closure: np.ndarray, slip: np.ndarray, E: float, G: float,
                 f: float) -> LayerStates:
    """State of every point: open where the layer would carry normal tension (closure
    ``e_n + g / h >= 0``), else stick while the trial shear ``G (gamma - slip)`` stays within
    ``f |sigma_n|``, else slip (always, without friction); the slip direction and ``kappa``."""
    closure = strain[..., NORMAL] + pre_closure
    sigma_n = E * closure
    tau = G * (strain[..., SHEAR] - slip)  # trial: no further slip
    size = np.linalg.norm(tau, axis=-1)
    limit = f * np.abs(sigma_n)
    kind = np.where((f > 0) & (size <= limit), STICK, SLIP)
    kind = np.where(closure >= -CLOSURE_TOL, OPEN, kind)
    slipping = (kind == SLIP) & (size > 0) & (f > 0)  # without friction no direction
    safe = np.where(slipping, size, 1.0)
    direction = np.where(slipping[..., None], tau / safe[..., None], 0.0)
    kappa = np.where(slipping, limit / safe, 0.0)
    return LayerStates(kind, direction, kappa)


def stick_where_reversed(new: LayerStates, old: LayerStates) -> LayerStates:
    """``new`` with the points that slipped one way in ``old`` and would slip the other way now
    made to stick: between the two iterates their slip passed through zero, inside the friction
    cone. Where the slip has one direction only (round a ring in plane strain) a slipping point
    has no tangential stiffness along it, and its direction would otherwise flip at every
    iteration; sticking, it finds whether it slips, and which way, from a bounded iterate."""
    turned = (new.kind == SLIP) & (old.kind == SLIP) & (np.einsum("...k,...k->...", new.direction, old.direction) < 0)
    if not turned.any():
        return new
    return LayerStates(np.where(turned, STICK, new.kind), np.where(turned[..., None], 0.0, new.direction),
                       np.where(turned, 0.0, new.kappa))


def layer_tangent(states: LayerStates, E: float, G: float, f: float) -> np.ndarray:
    """(n_points, n_x3, 6, 6) layer elasticity (the consistent tangent) of each state.

    Slip: ``tau = -f sigma_n d`` with ``d`` the direction of the trial stress (18)-(19),
    linearized about the current iterate: ``dtau/de_n = -f E d`` and
    ``dtau/dgamma = kappa G (I - d d')`` (the direction turns with the tangential strain;
    frozen, it flips between iterations where the slip turns).
    """
    kind, d = states.kind, states.direction
    D = np.zeros(kind.shape + (6, 6))
    D[..., NORMAL, NORMAL] = np.where(kind != OPEN, E, 0.0)
    slip = kind == SLIP
    for k, row in enumerate(SHEAR):
        D[..., row, NORMAL] = np.where(slip, -f * E * d[..., k], 0.0)
        for m, col in enumerate(SHEAR):
            turn = states.kappa * G * ((k == m) - d[..., k] * d[..., m])
            D[..., row, col] = np.where(kind == STICK, G * (k == m), np.where(slip, turn, 0.0))
    return D


def offset_strain(states: LayerStates, pre_closure: np.ndarray, slip: np.ndarray) -> np.ndarray:
    """(n_points, n_x3, 6) strain the layer adds to the displacement's: the gap (``g / h``) and
    the committed slip of closed points."""
    e = np.zeros(states.kind.shape + (6,))
    e[..., NORMAL] = pre_closure
    e[..., SHEAR] = np.where((states.kind != OPEN)[..., None], -slip, 0.0)
    return e


def slip_after(strain: np.ndarray, states: LayerStates, sigma: np.ndarray, slip: np.ndarray, G: float) -> np.ndarray:
    """The slip a converged step leaves: slipping points carry the part of their shear the
    stress does not, open points release all of it, sticking points keep theirs."""
    slip = np.where((states.kind == SLIP)[..., None], strain[..., SHEAR] - sigma[..., SHEAR] / G, slip)
    return np.where((states.kind == OPEN)[..., None], strain[..., SHEAR], slip)


class ContactError(StepFailed):
    """Contact states that do not settle, or a face pushed through the wall."""
