"""Probe evaluation: the case's recorded quantities from a reference solution.

Kinds: ``'point'`` with field ``'u'`` (interpolated with ``CellBasis.probes``), ``'sigma'``
and ``'peps'`` (value at the nearest quadrature point); ``'max'`` of ``'peps'`` over all
quadrature points; ``'edge_mean'`` of the normal stress ``sigma_nn`` on a face: the
resultant of the consistent nodal reactions ``K u + M a - Q`` of the face's nodes along the
normal (a curved face's at each node, :func:`reference_fem.face.face_of`), over the face area
(exact for the Lagrange multipliers of a wall or a contact pair, which are those reactions:
minus their sum over the area); ``'body_mean'`` of ``'u'`` or ``'v'``: the mass-weighted mean
``e^T M x / m``, ``e`` the component's direction at every node (momentum over mass for ``'v'``),
over the nodes of the probe's ``region`` only when it names one (a body of a scene of several).
Components are 1-based body components (ring: r, z, theta; prism: x1, x2, x3), rotated from
the mesh frame at the probe point.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from cases.params import UnsupportedCase

from .face import face_of
from .forms import SQRT2
from .frames import body_point_to_mesh, body_rotation


def mandel_to_tensor(m: np.ndarray) -> np.ndarray:
    """3x3 tensors, ``(n, 3, 3)``, in the mesh frame from Mandel vectors ``(n, 4 or 6)``."""
    n, nc = m.shape
    t = np.zeros((n, 3, 3))
    t[:, [0, 1, 2], [0, 1, 2]] = m[:, :3]
    shear = [(0, 1)] if nc == 4 else [(1, 2), (0, 2), (0, 1)]
    for k, (i, j) in enumerate(shear):
        t[:, i, j] = t[:, j, i] = m[:, 3 + k] / SQRT2
    return t


class Probes:
    """Evaluators of ``case.probes`` on one model, in the case's order.

    ``values(u, system, v, a)`` takes the full dof vectors of displacement ``u`` (m), velocity
    ``v`` and acceleration ``a`` (zero when omitted: a static state) and the equilibrium system
    (for stresses and plastic strains at quadrature points: ``stress_at(q)``, ``peps``); it
    returns one float per probe.
    """

    def __init__(self, model):
        self.model = model
        self.names = [p.name for p in model.case.probes]
        self._evaluators = [self._evaluator(p) for p in model.case.probes]

    def values(self, u: np.ndarray, system, v: np.ndarray | None = None, a: np.ndarray | None = None) -> list[float]:
        zero = np.zeros_like(u)
        v, a = (zero if x is None else x for x in (v, a))
        return [float(f(u, v, a, system)) for f in self._evaluators]

    def _evaluator(self, probe):
        model, case = self.model, self.model.case
        kind, fld = probe.kind, probe.field
        if kind == "max" and fld == "peps":
            return lambda u, v, a, s: s.peps.max()
        if kind == "edge_mean" and fld == "sigma" and tuple(probe.component) == ("n", "n"):
            return self._face_normal_stress(probe.edge)
        if kind == "body_mean" and fld in ("u", "v"):
            # a sparse row: its product is no BLAS call (whose threads stall on a busy machine)
            weights = sp.csr_matrix(body_mean_row(model, probe.component[0], probe.region))
            if fld == "u":
                return lambda u, v, a, s: (weights @ u)[0]
            return lambda u, v, a, s: (weights @ v)[0]
        if probe.region is not None:
            raise UnsupportedCase(f"reference solver: probe {probe.name!r}: only a body_mean of u or v takes a region")
        if kind != "point" or fld not in ("u", "sigma", "peps"):
            raise UnsupportedCase(f"reference solver: probe {probe.name!r} ({kind} of {fld}) is not available")
        x = body_point_to_mesh(case, model.rep, probe.point)
        R = body_rotation(case, model.rep, x[:, None])[0]
        if fld == "u":
            P = value_probes(model.basis, x)  # component-major rows
            row = R[probe.component[0] - 1, : model.dim]
            return lambda u, v, a, s: row @ (P @ u)
        q = int(np.argmin(np.linalg.norm(model.x_qp - x[:, None], axis=0)))
        if fld == "peps":
            return lambda u, v, a, s: s.peps[q]
        if "n" in probe.component:
            raise UnsupportedCase(f"reference solver: probe {probe.name!r}: normal stress needs a face, not a point")
        i, j = (c - 1 for c in probe.component)
        return lambda u, v, a, s: (R @ mandel_to_tensor(s.stress_at(q)[None, :])[0] @ R.T)[i, j]

    def _face_normal_stress(self, edge: str):
        """``sigma_nn`` averaged over the face ``edge``, from the face's nodal reactions."""
        model = self.model
        face = face_of(model, edge)
        e = np.zeros((model.basis.N // model.dim, model.dim))
        e[face.nodes] = face.normals
        e = e.ravel() / face.area
        k_row, m_row = sp.csr_matrix(model.stiffness_times(e)), sp.csr_matrix(e @ model.M)  # K, M symmetric
        q = e @ model.Q
        return lambda u, v, a, s: (k_row @ u + m_row @ a)[0] - q


#: a probe point this close to a node (relative to the mesh's size) is read at the node
AT_NODE = 1e-12


def value_probes(basis, x: np.ndarray) -> sp.csr_matrix:
    """The rows ``(dim, n_dof)`` that read a vector field of ``basis`` at the point ``x`` (dim,),
    component by component: the node's dofs where ``x`` is a node (the shape functions there are
    one and zeros: no map to invert), else ``basis.probes`` from the shape functions' values
    alone. scikit-fem's evaluates their gradients too, which need the map's inverse Jacobian: at
    a point on the axis of a section swept round it (:mod:`reference_fem.ties`) that Jacobian is
    singular, and the value is read all the same."""
    dim = basis.elem.dim
    gap = np.linalg.norm(basis.doflocs[:, ::dim] - x[:, None], axis=0)
    if gap.min() <= AT_NODE * np.abs(basis.doflocs).max():
        dofs = dim * np.argmin(gap) + np.arange(dim)
        return sp.csr_matrix((np.ones(dim), (np.arange(dim), dofs)), shape=(dim, basis.N))
    cell = int(basis.mesh.element_finder(mapping=basis.mapping)(*x[:, None])[0])
    local = basis.mapping.invF(x[:, None, None], tind=np.array([cell]))[:, 0, :]  # (dim, 1)
    phi = np.array([basis.elem.elem.lbasis(local, i)[0][0] for i in range(basis.Nbfun // dim)])  # scalar functions
    rows = np.tile(np.arange(dim), basis.Nbfun // dim)  # local dof l: function l // dim, component l % dim
    values = np.repeat(phi, dim)
    return sp.csr_matrix((values, (rows, basis.element_dofs[:, cell])), shape=(dim, basis.N))


def body_mean_row(model, component: int, region: str | None = None) -> np.ndarray:
    """The row ``w`` with ``w @ x`` the mass-weighted mean of body ``component`` (1-based) of the
    full dof vector ``x``: ``e^T M x / m``, ``e`` the component's direction at every node (of
    ``region``'s nodes only, when given: a body sharing no node with the rest, whose mass rows
    are its own, :meth:`reference_fem.model.Model.region_nodes`)."""
    R = body_rotation(model.case, model.rep, model.nodes_x)
    e = R[:, component - 1, : model.dim]
    nodes = slice(None)
    if region is not None:
        nodes = model.region_nodes(region, "a body_mean probe")
        e = np.where(np.isin(np.arange(e.shape[0]), nodes)[:, None], e, 0.0)
    mass = (model.M @ np.ones(model.basis.N)).reshape(-1, model.dim)[:, 0]
    return (e.ravel() @ model.M) / mass[nodes].sum()
