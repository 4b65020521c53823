"""A contact step that always settles: Newton's method with a line search on the step's energy,
the friction limits frozen at each iterate.

The layer's own iteration (:meth:`smfem.contact.ContactSystem.solve`) is Newton's method on
Coulomb's law with its consistent tangent, which is fast and settles on the rod and the tilted
wall. But a slipping point has no tangential stiffness along its slip, and where the slip has
one direction only (round a ring in plane strain, against a deformable body) the iterates can
swing each slipping point from one side to the other for ever: on ``ring_in_ring`` no damping
of the iterates settled the step where the rings first slide (2000 iterations, relaxation down
to 1/4096). The step is then solved again here, from its start.

On the face dofs (the Woodbury reduction of :class:`~smfem.contact.ContactSystem`) a step is
``w = C y - S f(w)``: the face displacements ``w`` of all modes are the body's answer ``C y`` to
the step's load, less its answer ``S`` (``C A0^-1 C'``) to the layer's forces ``f(w)``. With the
friction limits ``l = f |sigma_n|`` held, the layer's law is Tresca's, which has an energy, so
``w`` is the minimizer of the convex function

    Pi(w) = 1/2 (w - C y)' S^-1 (w - C y) + sum_q a_q psi_q(e_q(w)),

``psi`` per layer point: ``E c^2 / 2`` of a closed point's closure ``c < 0``; ``|t|^2 / (2 G)``
of its trial shear stress ``t = G (gamma - slip)`` within the limit, ``l |t| / G - l^2 / (2 G)``
beyond it; nothing where open. Newton's step of ``Pi`` (the stick or slip tangent, without
Coulomb's normal coupling) is a descent direction; it is shortened until ``Pi`` falls enough
(Armijo) until ``Pi`` is at its minimum (Newton's step from there is round-off); then ``l`` is
updated from the normal stresses there and ``Pi`` minimized again. Settled: the limits the
minimum sets are those it was found with, so Coulomb's law holds at the end.
"""

from __future__ import annotations

import numpy as np

from .layer_law import CLOSURE_TOL, NORMAL, SHEAR, ContactError

#: the share of the predicted decrease a step must achieve (Armijo's constant)
ARMIJO = 1e-4
#: the shortest step tried along a Newton direction
SHORTEST = 2.0**-30
#: the strain within which the tangent takes a point as closed (as sticking): 1e-10 m across a
#: 0.1 mm layer, far below a contact's own strain (its stress over E_l, 5e-6 at 1 MPa)
EDGE_BAND = 1e-6
#: the relative round-off of the step's energy
ROUNDOFF = 1e-12
#: settled: the friction limits a minimum sets are those it was found with, to this share of the
#: largest (the minima are round-off close to each other: on ring_in_ring at 80 harmonics the
#: limits of successive minima wandered by 2e-10 of the largest, never below 1e-10)
LIMITS_TOL = 1e-8
#: iterations allowed to one step
MAX_ITERATIONS = 500
#: a minimum: Newton's step from it, relative to the face motion
TOLERANCE = 1e-10


def tresca(layer, strain: np.ndarray, limits: np.ndarray, tangent: bool = True):
    """Stress (n_points, n_x3, 6), tangent (.., 6, 6; None unless ``tangent``: a line search's
    trial needs none) and energy density (n_points, n_x3) of every layer point at ``strain``
    with the friction limits ``limits`` held.

    Tresca's friction acts where its limit is set, whether the point is closed at ``strain`` or
    not (at the settled step a point's limit is its own ``f |sigma_n|``, zero where open): tied
    to the closure, the energy would jump where a point with a limit opened, and the line
    search would stall at the jump. The tangent takes a point within :data:`EDGE_BAND` of
    closing as closed, and one within it of sticking as sticking: at the edge (two faces that
    touch at a step's start; a point a line search stopped at) a tangent without its stiffness
    sends Newton's step through the other face, and the iterates stall there."""
    closure = strain[..., NORMAL] + layer.pre_closure
    closed = closure < -CLOSURE_TOL
    E, G = layer.E, layer.G
    trial = G * (strain[..., SHEAR] - layer.slip_strain)
    size = np.linalg.norm(trial, axis=-1)
    rubbing = limits > 0
    slipping = rubbing & (size > limits)
    safe = np.where(slipping, size, 1.0)
    d = np.where(slipping[..., None], trial / safe[..., None], 0.0)
    kappa = np.where(slipping, limits / safe, 1.0)
    sigma = np.zeros(strain.shape)
    sigma[..., NORMAL] = np.where(closed, E * closure, 0.0)
    sigma[..., SHEAR] = np.where(rubbing[..., None], kappa[..., None] * trial, 0.0)
    energy = np.where(closed, 0.5 * E * closure**2, 0.0) + np.where(
        slipping, (limits * size - 0.5 * limits**2) / G, np.where(rubbing, 0.5 * size**2 / G, 0.0))
    if not tangent:
        return sigma, None, energy
    near = closure < -CLOSURE_TOL + EDGE_BAND
    sticking = rubbing & ~(slipping & (size > limits + G * EDGE_BAND))
    D = np.zeros(strain.shape + (6,))
    D[..., NORMAL, NORMAL] = np.where(near, E, 0.0)
    for k, row in enumerate(SHEAR):
        for m, col in enumerate(SHEAR):
            turn = np.where(sticking, G * (k == m), kappa * G * ((k == m) - d[..., k] * d[..., m]))
            D[..., row, col] = np.where(rubbing, turn, 0.0)
    return sigma, D, energy


def friction_limits(layer, strain: np.ndarray) -> np.ndarray:
    """``f |sigma_n|`` of every point (0 where open)."""
    closure = strain[..., NORMAL] + layer.pre_closure
    return np.where(closure < -CLOSURE_TOL, -layer.f * layer.E * closure, 0.0)


def descend(system, y: np.ndarray, start: np.ndarray, step_index: int, t: float) -> tuple[np.ndarray, int]:
    """The step's displacement (all modes stacked) from the body's answer ``y = A0^-1 b`` to its
    load, starting from the face of ``start`` (the last step's displacement), and the iterations."""
    layer = system.layer
    shape = (len(layer.C), len(layer.F))
    U, stiffness = system.face_compliance_inverse()  # w = U a: the face motions the body allows
    target = U.T @ layer.face_values(y).ravel()
    a = U.T @ layer.face_values(start).ravel()
    limits = friction_limits(layer, layer.face_strain((U @ a).reshape(shape)))

    def energy(v, tangent=False):
        sigma, D, psi = tresca(layer, layer.face_strain((U @ v).reshape(shape)), limits, tangent)
        return 0.5 * (v - target) @ (stiffness * (v - target)) + float(np.sum(layer.area * psi)), sigma, D

    for iteration in range(1, MAX_ITERATIONS + 1):
        pi, sigma, D = energy(a, tangent=True)
        gradient = stiffness * (a - target) + U.T @ layer.face_force(sigma).ravel()
        step = -np.linalg.solve(np.diag(stiffness) + U.T @ layer.face_matrix(None, D) @ U, gradient)
        slope = float(gradient @ step)
        # Pi's round-off: its parts are far larger than what a last step changes (the layer is
        # 1e4 times stiffer than the body), so a decrease below it is no decrease to test
        noise = ROUNDOFF * (abs(pi) + 0.5 * target @ (stiffness * target))
        alpha = 1.0
        while alpha >= SHORTEST and energy(a + alpha * step)[0] > pi + ARMIJO * alpha * slope + noise:
            alpha *= 0.5
        # at the minimum: Newton's step is round-off, or what it could still gain (its decrement,
        # -slope / 2) is below Pi's round-off
        small = np.abs(step).max() <= TOLERANCE * max(np.abs(a).max(), layer.h) or -slope <= noise
        if alpha < SHORTEST:  # no descent along Newton's direction: at the minimum, or stuck
            if not small:
                raise ContactError(f"step {step_index} (t = {t:.6g} s): the line search found no descent "
                                   "(state chattering)")
            alpha = 0.0
        a = a + alpha * step
        if not small:  # Pi at these limits not minimized yet: hold them (a moving target cycles)
            continue
        new = friction_limits(layer, layer.face_strain((U @ a).reshape(shape)))
        if np.abs(new - limits).max(initial=0.0) <= LIMITS_TOL * max(np.abs(new).max(initial=0.0), 1.0):
            break  # the minimum of Pi at the limits its own normal stresses set: Coulomb's law
        limits = new
    else:
        raise ContactError(f"step {step_index} (t = {t:.6g} s): contact states did not settle in {MAX_ITERATIONS} "
                           "iterations of the line-search Newton method either (state chattering)")
    w = U @ a
    sigma = tresca(layer, layer.face_strain(w.reshape(shape)), limits, tangent=False)[0]
    f = layer.face_force(sigma)
    return y - np.concatenate([Z @ fi for Z, fi in zip(system.Z, f)]), iteration
