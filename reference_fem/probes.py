"""Probe evaluation: the case's recorded quantities from a reference solution.

Kinds: ``'point'`` with field ``'u'`` (interpolated with ``CellBasis.probes``), ``'sigma'``
and ``'peps'`` (value at the nearest quadrature point); ``'max'`` of ``'peps'`` over all
quadrature points. Components are 1-based body components (ring: r, z, theta; prism: x1, x2,
x3), rotated from the mesh frame at the probe point.
"""

from __future__ import annotations

import numpy as np

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

    ``values(u, system)`` takes the full dof vector ``u`` (m) and the equilibrium system (for
    stresses and plastic strains at quadrature points) and returns one float per probe.
    """

    def __init__(self, model):
        self.model = model
        self.names = [p.name for p in model.case.probes]
        self._evaluators = [self._evaluator(p) for p in model.case.probes]

    def values(self, u: np.ndarray, system) -> list[float]:
        return [float(f(u, system)) for f in self._evaluators]

    def _evaluator(self, probe):
        model, case = self.model, self.model.case
        kind, fld = probe.kind, probe.field
        if kind == "max" and fld == "peps":
            return lambda u, s: s.peps.max()
        if kind != "point" or fld not in ("u", "sigma", "peps"):
            raise UnsupportedCase(f"reference solver: probe {probe.name!r} ({kind} of {fld}) is not available")
        x = body_point_to_mesh(case, model.rep, probe.point)
        R = body_rotation(case, model.rep, x[:, None])[0]
        if fld == "u":
            P = model.basis.probes(x[:, None]).tocsr()  # component-major rows
            row = R[probe.component[0] - 1, : model.dim]
            return lambda u, s: row @ (P @ u)
        q = int(np.argmin(np.linalg.norm(model.x_qp - x[:, None], axis=0)))
        if fld == "peps":
            return lambda u, s: s.peps[q]
        if "n" in probe.component:
            raise UnsupportedCase(f"reference solver: probe {probe.name!r}: normal stress needs a face, not a point")
        i, j = (c - 1 for c in probe.component)
        return lambda u, s: (R @ mandel_to_tensor(s.sigma[q : q + 1])[0] @ R.T)[i, j]
