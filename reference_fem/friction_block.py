"""Test scene for Coulomb friction: an elastic block pressed on a rigid plane and pulled.

A block (plane strain in 2D, or a 3D box) rests on the rigid plane ``x_dim = 0`` with no gap.
A uniform traction on its top face first presses it (pressure ``q``, total normal force ``N``
per unit width in 2D) and then pulls it along x (total ``P = pull f N``), both switched on by
smooth ramps and then held. Below ``f N`` the block sticks (it takes the pull by friction and
stays put); above, it slides with the rigid-body acceleration ``(P - f N) / m``.
The time step is far longer than the block's elastic periods and the ramps are slow, so the
elastic response is quasi-static while the sliding is not.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skfem import (CellBasis, ElementHex2, ElementQuad2, FacetBasis, LinearForm, MeshHex1,
                   MeshHex2, MeshQuad1, MeshQuad2, asm)
from skfem.helpers import dot

from cases.material import Material

from . import forms, laws
from .contact import wall_rows
from .element import VectorElement
from .mass import consistent_mass, redistributed_mass
from .model import INTORDER
from .newmark import march, newmark_constants
from .wall import WallSystem


@dataclass
class BlockModel:
    """The attributes of a :class:`~reference_fem.model.Model` that the equilibrium systems use."""

    basis: CellBasis
    weights: np.ndarray
    law: object
    M: object
    free: np.ndarray

    @property
    def D(self) -> np.ndarray:
        return self.law.elastic_matrix()

    @property
    def dim(self) -> int:
        return self.basis.mesh.dim()

    @property
    def n_qp(self) -> int:
        return self.weights.shape[0]

    def stiffness(self):
        return forms.stiffness(self.basis, False, self.weights, self.D)


@dataclass(frozen=True)
class BlockRun:
    """History of a pulled block (forces per unit width in 2D).

    Attributes
    ----------
    t : (n + 1,) times (s)
    normal, friction : (n + 1,) total normal wall force and friction force along x (N)
    velocity : (n + 1,) mean velocity of the block along x (momentum / mass, m/s)
    states : (n + 1, n_c) contact state of every contact node (:mod:`reference_fem.contact`)
    iterations : active-set iterations per step
    N, P, mass : final normal load, pull and the block's mass
    """

    t: np.ndarray
    normal: np.ndarray
    friction: np.ndarray
    velocity: np.ndarray
    states: np.ndarray
    iterations: list
    N: float
    P: float
    mass: float


@LinearForm
def _traction(v, w):
    return dot(w.t, v)


def pulled_block(friction: float, pull: float, dim: int = 2, size=(0.1, 0.1, 0.05), counts=(4, 4, 2),
                 E: float = 2.1e11, nu: float = 0.3, rho: float = 7.8e3, q: float = 1e6,
                 dt: float = 1e-4, ramp: int = 10, hold: int = 10) -> BlockRun:
    """Press a block with ``q`` (Pa), then pull it with ``pull`` times ``friction`` q on its top.

    Parameters
    ----------
    friction : Coulomb coefficient f
    pull : the pull as a multiple of the friction limit f N
    dim : 2 (plane strain, x and height) or 3
    size, counts : box edges along x, (y,) height (m) and elements along each (2D: first and last)
    E, nu, rho : steel by default
    q : top pressure (Pa)
    dt : time step (s), long against the elastic periods (~1e-5 s)
    ramp, hold : steps of each smooth ramp (press, then pull) and of the final hold
    """
    edges, n = (size[::2], counts[::2]) if dim == 2 else (size, counts)
    lin = (MeshQuad1 if dim == 2 else MeshHex1).init_tensor(*(np.linspace(0, a, k + 1) for a, k in zip(edges, n)))
    mesh = (MeshQuad2 if dim == 2 else MeshHex2).from_mesh(lin)
    element = VectorElement(ElementQuad2() if dim == 2 else ElementHex2())
    basis = CellBasis(mesh, element, intorder=INTORDER)
    weights = forms.quadrature_weights(basis, False)
    bottom = mesh.facets_satisfying(lambda x: np.isclose(x[-1], 0.0), boundaries_only=True)
    top = mesh.facets_satisfying(lambda x: np.isclose(x[-1], edges[-1]), boundaries_only=True)
    M = redistributed_mass(consistent_mass(basis, rho, False), basis, bottom, rho, False, INTORDER)
    model = BlockModel(basis, weights, laws.get(Material(E, nu, rho), dim), M, np.arange(basis.N))

    fb = FacetBasis(mesh, element, facets=top, intorder=INTORDER)
    # unit tractions on the top: down (pressing) and along x (pulling)
    down, along = (asm(_traction, fb, t=s * np.eye(dim)[k][:, None, None] * np.ones(fb.dx.shape))
                   for s, k in ((-1.0, dim - 1), (1.0, 0)))
    area = float(np.prod(edges[:-1]))
    N, P = q * area, pull * friction * q * area

    def load(t):
        s = t / (ramp * dt)
        return q * _smooth(s) * down + P / area * _smooth(s - 1.0) * along

    nodes = np.unique(basis.get_dofs(facets=bottom).all("u^1") // dim)
    normal = -np.eye(dim)[dim - 1]
    rows = wall_rows(nodes, normal, np.zeros(nodes.size), model.free, basis.N, friction, 1e-12 * max(edges))
    system = WallSystem(model, newmark_constants(dt).a0, rows)
    n_c = rows.n_c
    along_x = np.zeros(basis.N)
    along_x[0::dim] = 1.0
    mass = along_x @ (M @ along_x)
    t, normal_f, friction_f, velocity, states, iterations = [0.0], [0.0], [0.0], [0.0], [np.zeros(n_c, int)], []
    zero = np.zeros(basis.N)
    for _, t_n, _u, v, _a, its in march(system, load, zero, zero, dt, 2 * ramp + hold):
        p = system.state.p
        t.append(t_n)
        normal_f.append(p[:n_c].sum())
        friction_f.append(p[n_c:] @ (rows.H[n_c:] @ along_x) if friction > 0 else 0.0)
        velocity.append(along_x @ (M @ v) / mass)
        states.append(system.state.state.copy())
        iterations.append(its)
    return BlockRun(np.array(t), np.array(normal_f), np.array(friction_f), np.array(velocity), np.array(states),
                    iterations, N, P, mass)


def _smooth(s):
    """Smooth step from 0 (s <= 0) to 1 (s >= 1) with zero slope at both ends."""
    s = np.clip(s, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * s)
