"""Probes by harmonic synthesis (12): linear operators from mode amplitudes to probe values.

Every probe that is linear in the displacements (or velocities) becomes one row per mode, so a
probe history costs one sparse product per step.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from . import fourier
from .assembly import element_dofs
from .elements import Element
from cases.section_mesh import SectionMesh
from .model import ModelError


def locate(mesh: SectionMesh, element: Element, point) -> tuple[int, float, float]:
    """Element and local coordinates ``(xi, eta)`` in [-1/2, 1/2] of a section point.

    Newton inversion of every element's map (``element``'s shape functions) at once; the
    element whose local coordinates lie inside (or least outside) is chosen.
    """
    X = mesh.element_x()
    p = np.asarray(point, float)
    xi = np.zeros((len(X), 2))
    for _ in range(20):
        N, dxi, deta = element.shape_functions(xi[:, 0], xi[:, 1])
        x = np.einsum("ei,eia->ea", N, X)
        J = np.stack([np.einsum("ei,eia->ea", dxi, X), np.einsum("ei,eia->ea", deta, X)], axis=2)
        J[np.linalg.det(J) == 0] = np.eye(2)  # a fold of a far element's extended map: step on
        xi = np.clip(xi + np.linalg.solve(J, (p - x)[..., None])[..., 0], -2.0, 2.0)
    outside = np.abs(xi).max(axis=1) - 0.5
    e = int(np.argmin(np.where(np.isfinite(outside), outside, np.inf)))
    if outside[e] > 1e-6:
        raise ValueError(f"probe point {tuple(point)} lies outside the cross-section")
    a, b = np.clip(xi[e], -0.5, 0.5)
    return e, float(a), float(b)


def stress_component_weights(R: np.ndarray, comp) -> np.ndarray:
    """(6,) weights that turn local Voigt stresses into the global component ``comp`` (1-based).

    ``R`` (2, 2) has rows t1, t2 of the local frame; sigma_global = Q' sigma_local Q with Q the
    3-D rotation ``[[R, 0], [0, 1]]``.
    """
    Q = np.eye(3)
    Q[:2, :2] = R
    a, b = comp[0] - 1, comp[1] - 1
    voigt = {(0, 0): 0, (1, 1): 1, (2, 2): 2, (0, 1): 3, (1, 0): 3, (0, 2): 4, (2, 0): 4, (1, 2): 5, (2, 1): 5}
    w = np.zeros(6)
    for i in range(3):
        for j in range(3):
            w[voigt[i, j]] += Q[i, a] * Q[j, b]
    return w


class PlasticStrainProbes:
    """Equivalent plastic strain probes from the sample points (Gauss points x the points ``x3``).

    A point probe interpolates between the element's section points (the moment scheme: bilinearly
    between its four Gauss points) and linearly
    between the two nearest x3 points; ``max`` is the maximum over every sample point.
    """

    def __init__(self, model, probes, x3: np.ndarray, images: np.ndarray | None = None):
        """``x3``: the points along the whole range; ``images``: the sample point each is an
        image of (:meth:`evaluate` then takes the sample points only: no unfolding per step)."""
        images = np.arange(len(x3)) if images is None else images
        self.names = [p.name for p in probes]
        self.targets = []
        period = 2 * np.pi if model.body == "ring" else model.length
        for p in probes:
            if p.kind == "max":
                self.targets.append(None)
                continue
            e, xi, eta = locate(model.mesh, model.element, p.point[:2])
            wg = model.element.sample_interpolation(xi, eta)
            ring = model.body == "ring"
            x = p.point[2] % period if ring else p.point[2]
            # around a ring the points wrap: the neighbours of theta = 0 are the last and first
            at = np.concatenate([[x3[-1] - period], x3, [x3[0] + period]]) if ring else x3
            k = int(np.clip(np.searchsorted(at, x), 1, len(at) - 1))
            lam = float(np.clip((x - at[k - 1]) / (at[k] - at[k - 1]), 0.0, 1.0))
            k = (k - 1) % len(x3) if ring else k  # index into x3 of the upper neighbour
            self.targets.append((e, wg, images[k - 1], images[k], lam))  # k - 1 = -1 wraps

    def evaluate(self, peps: np.ndarray) -> np.ndarray:
        """Probe values from the plastic strain at the sample points (n_elements, section
        points, n_x3): the maximum over them is the maximum over all their images."""
        out = []
        for target in self.targets:
            if target is None:
                out.append(peps.max())
                continue
            e, wg, below, above, lam = target
            out.append(wg @ ((1 - lam) * peps[e, :, below] + lam * peps[e, :, above]))
        return np.array(out)


class ProbeSet:
    """Linear probe operators of a model: ``values = sum_mode P[mode] @ u_mode`` (reduced)."""

    def __init__(self, model, probes):
        self.model = model
        self.names = [p.name for p in probes]
        self.fields = [p.field for p in probes]
        rows = [self._rows(p) for p in probes]
        width = 3 * model.mesh.n_nodes
        per_mode = [np.vstack([r[i] for r in rows] or [np.zeros((0, width))]) @ s.T for i, s in enumerate(model.systems)]
        P = sp.csr_matrix(np.hstack(per_mode))  # acts on the amplitudes of all modes stacked
        velocity = np.array([f == "v" for f in self.fields], bool)
        self.on_u = sp.csr_matrix(P.multiply(~velocity[:, None]))
        self.on_v = sp.csr_matrix(P.multiply(velocity[:, None])) if velocity.any() else None

    def _rows(self, probe) -> list[np.ndarray]:
        """One full-dof row (3 n_nodes,) per mode."""
        m = self.model
        if probe.kind != "point" or probe.field not in ("u", "v", "sigma"):
            raise ValueError(f"probe {probe.name!r} ({probe.kind} {probe.field}) is not available in the linear solver")
        e, xi, eta = locate(m.mesh, m.element, probe.point[:2])
        dofs = element_dofs(m.mesh.elements[[e]])[0]
        out = []
        for s in m.systems:
            psi1, psi3 = fourier.psi(s.mode, probe.point[2], m.body, m.length)
            row = np.zeros(3 * m.mesh.n_nodes)
            if probe.field in ("u", "v"):
                N, _, _ = m.element.shape_functions(xi, eta)
                c = probe.component[0] - 1
                row[dofs[c::3]] = N * (psi1 if c < 2 else psi3)
            else:
                p = fourier.wavenumber(s.mode, m.body, m.length)
                eps = m.ops.subset([e]).strain(p, xi, eta)[0] * np.where(fourier.ROW_TYPE == 0, psi1, psi3)[:, None]
                w = stress_component_weights(m.ops.rotation[e], probe.component)
                row[dofs] = w @ m.element_D([e]).reshape(-1, 6, 6)[0] @ eps
            out.append(row)
        return out

    def evaluate(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Probe values from the stacked reduced displacements and velocities of all modes."""
        values = self.on_u @ u
        return values if self.on_v is None else values + self.on_v @ v


#: probes a system answers itself: (kind, field) -> the system's method
SYSTEM_PROBES = {("edge_mean", "sigma"): "contact_pressure", ("body_mean", "v"): "mean_axial_velocity"}


class CaseProbes:
    """Every probe of a case, in the case's order, from a step's state and its system: point
    probes of u, v, sigma (:class:`ProbeSet`), plastic strains (:class:`PlasticStrainProbes` of
    ``system.peps``) and what a system answers itself (:data:`SYSTEM_PROBES`: the contact
    pressure and the mean velocity of a contact run)."""

    def __init__(self, case, model, system):
        linear = [q for q in case.probes if q.field != "peps" and q.kind == "point"]
        plastic = [q for q in case.probes if q.field == "peps"]
        self.points = ProbeSet(model, linear)
        self.plastic = None
        if plastic and hasattr(system, "peps"):
            self.plastic = PlasticStrainProbes(model, plastic, system.peps_x3, system.peps_images)
        self.names = list(case.probe_names)
        self.probes = case.probes
        self.columns = []
        for q in case.probes:
            if q.field == "peps":
                if not hasattr(system, "peps"):
                    raise ModelError(f"{case.name}: probe {q.name!r} needs plasticity (set plastic=true)")
                self.columns.append(("plastic", plastic.index(q)))
            elif q.kind == "point":
                self.columns.append(("point", linear.index(q)))
            elif hasattr(system, SYSTEM_PROBES.get((q.kind, q.field), "")):
                self.columns.append(("system", SYSTEM_PROBES[q.kind, q.field]))
            else:
                raise ModelError(f"{case.name}: probe {q.name!r} ({q.kind} of {q.field}) is not available here")
        self.only_points = self.columns == [("point", k) for k in range(len(self.columns))]

    def values(self, state, system) -> np.ndarray:
        point = self.points.evaluate(state.u, state.v)
        if self.only_points:  # the common case, once per step: no per-probe dispatch
            return point
        plastic = self.plastic.evaluate(system.peps_sampled) if self.plastic else ()
        return np.array([point[i] if kind == "point" else plastic[i] if kind == "plastic"
                         else getattr(system, i)(state, q) for (kind, i), q in zip(self.columns, self.probes)])
