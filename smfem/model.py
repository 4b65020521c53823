"""The discrete SMFEM model of a case: mesh, element operators, per-mode matrices and loads.

Built once per case and resolution; time stepping and statics only read it.

A body homogeneous along x3 has decoupled modes: only those that carry a load or an initial
velocity are kept. Where the material varies along x3 (cut-outs) the modes couple through
``D(lm)`` and ``rho(lm)``; then the modes kept are those the loaded ones reach through nonzero
coupling, and ``coupling`` holds the off-diagonal blocks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from cases.geometry import RING
from cases.params import UnsupportedCase

from . import assembly, constraints, element, fourier, inhomogeneity, loads, symmetry
from .constitutive import isotropic_D
from .mesh import SectionMesh, section_mesh


class ModelError(UnsupportedCase):
    """The case asks for something this model cannot represent (a clear, user-facing message)."""


@dataclass
class ModeSystem:
    """One mode: map ``T`` (full <- reduced), diagonal block ``K``, lumped ``M`` diagonal, load
    ``Q`` and initial velocity ``V0`` (reduced)."""

    mode: fourier.Mode
    T: sp.csr_matrix
    K: sp.csr_matrix
    M: np.ndarray
    Q: np.ndarray
    V0: np.ndarray


class Model:
    """SMFEM model of ``case``.

    Parameters
    ----------
    nonlinear : keep every mode the symmetry of the problem allows (plasticity couples them) and
        set up the x3 sample points for stresses

    The off-diagonal stiffness blocks are assembled only on request
    (:meth:`assemble_coupled_stiffness`): a direct solve needs them, the block-iterative solver
    takes the coupling from the stresses instead.
    """

    def __init__(self, case, nonlinear: bool = False):
        self.case = case
        self.body = case.body
        self.length = case.length
        self.mesh: SectionMesh = section_mesh(case.section, case.refine)
        self.ops = element.operators(self.mesh.element_x(), case.body, case.material.nu)
        mat = case.material
        self.D = isotropic_D(mat.E, mat.nu)
        self.rho = mat.rho
        self.inhomogeneous = bool(case.cutouts) and case.contrast < 1.0
        n_harm = case.harmonics
        families = ("c", "s") if case.body == RING else ("p",)
        candidates = fourier.modes(case.body, n_harm, families)
        Q = loads.load_amplitudes(case, self.mesh, candidates)
        V = loads.velocity_amplitudes(case, self.mesh, candidates)
        size = {m: max(np.abs(Q[m]).max(), np.abs(V[m]).max()) for m in candidates}
        scale = max(size.values())
        if scale == 0.0:
            raise ModelError(f"{case.name}: no load and no initial velocity: nothing moves")
        loaded = [i for i, m in enumerate(candidates) if size[m] > 1e-12 * scale]
        self.nonlinear = nonlinear
        if self.inhomogeneous or nonlinear:
            self.x3, self.x3_weights = inhomogeneity.x3_quadrature(case, n_harm)
            self.factor = inhomogeneity.element_factor(case, self.mesh, self.x3)
        if nonlinear:
            allowed = set(symmetry.nonlinear_modes(case, candidates))
            active = [i for i, m in enumerate(candidates) if m in allowed]
        if self.inhomogeneous:
            I = inhomogeneity.coupling_integrals(candidates, case, self.factor, self.x3, self.x3_weights)
            # outside the cut-outs f = 1 and different harmonics are orthogonal along x3: their
            # integrals are round-off there; exact zeros keep the coupled matrix sparse
            outside = (self.factor == 1.0).all(axis=1)
            I[~np.eye(len(candidates), dtype=bool)[:, :, None] & outside[None, None, :]] = 0.0
            if not nonlinear:
                # an isotropic D and the lumped mass pair psi1 with psi1 and psi3 with psi3 only
                strength = np.maximum(np.abs(I[..., 0, 0]), np.abs(I[..., 1, 1])).max(axis=2)
                active = self._reachable(loaded, strength)
            self._integrals = {(i, j): I[a, b] for i, a in enumerate(active) for j, b in enumerate(active)}
        else:
            active = active if nonlinear else loaded
            self._integrals = {(i, i): self._homogeneous_integrals(candidates[a]) for i, a in enumerate(active)}
        self.modes = [candidates[a] for a in active]
        fixed = constraints.fixed_dofs(case, self.mesh)
        self.systems: list[ModeSystem] = []
        for i, mode in enumerate(self.modes):
            T = constraints.mode_map(case, self.mesh, mode, fixed)
            K = (T.T @ self.full_stiffness(i, i) @ T).tocsr()
            M = T.multiply(T).T @ self.full_mass(i, i)  # T'diag(m)T stays diagonal: T's columns do not overlap
            self.systems.append(ModeSystem(mode, T, K, M, T.T @ Q[mode], self._project(T, V[mode])))
        self.coupling: dict[tuple[int, int], tuple[sp.csr_matrix, sp.csr_matrix]] = {}
        for (i, j) in self._integrals:
            if i != j:
                Ti, Tj = self.systems[i].T, self.systems[j].T
                mass = (Ti.T @ sp.diags(self.full_mass(i, j)) @ Tj).tocsr()
                mass.eliminate_zeros()
                self.coupling[i, j] = (None, mass)

    def mass_matrix(self):
        """Stacked mass of all modes: the diagonal (n,) when the modes decouple, else the sparse
        block matrix with the mass coupling rho(lm)."""
        S = self.systems
        if not self.coupling:
            return np.concatenate([s.M for s in S])
        blocks = [[sp.diags(s.M) if i == j else (self.coupling[i, j][1] if (i, j) in self.coupling else None)
                   for j in range(len(S))] for i, s in enumerate(S)]
        return sp.bmat(blocks, format="csr")

    def coupled_nonzeros(self) -> int:
        """Nonzeros of the whole coupled stiffness, bounded before assembling it: an
        off-diagonal block has at most 144 entries per element where its x3 integral is not
        zero (the cut-outs'), and at most the pattern of its row's diagonal block."""
        live = lambda i, j: int((np.abs(self._integrals[i, j]).reshape(self.mesh.n_elements, -1).max(axis=1) > 0).sum())
        return (sum(min(self.systems[i].K.nnz, 144 * live(i, j)) for i, j in self.coupling)
                + sum(s.K.nnz for s in self.systems))

    def assemble_coupled_stiffness(self) -> None:
        """Fill the off-diagonal stiffness blocks ``K(lm)`` of ``coupling``."""
        for (i, j), (K, M) in self.coupling.items():
            if K is None:
                Ti, Tj = self.systems[i].T, self.systems[j].T
                self.coupling[i, j] = ((Ti.T @ self.full_stiffness(i, j) @ Tj).tocsr(), M)

    @staticmethod
    def _reachable(loaded: list[int], strength: np.ndarray, tol: float = 1e-12) -> list[int]:
        """Modes reached from the loaded ones through nonzero coupling (sorted)."""
        linked = strength > tol * strength.max()
        seen, todo = set(loaded), list(loaded)
        while todo:
            for j in np.flatnonzero(linked[todo.pop()]):
                if j not in seen:
                    seen.add(int(j))
                    todo.append(int(j))
        return sorted(seen)

    @staticmethod
    def _project(T: sp.csr_matrix, v: np.ndarray) -> np.ndarray:
        """Reduced coordinates of a full vector that lies in the range of ``T``."""
        return sp.linalg.lsqr(T, v, atol=1e-14, btol=1e-14)[0] if v.any() else np.zeros(T.shape[1])

    def _homogeneous_integrals(self, mode: fourier.Mode) -> np.ndarray:
        """(n_elements, 2, 2) exact x3 integrals of basis products of one mode."""
        i1, i3 = fourier.psi_squared_integrals(mode, self.body, self.length)
        out = np.zeros((self.mesh.n_elements, 2, 2))
        out[:, 0, 0], out[:, 1, 1] = i1, i3
        return out

    def full_stiffness(self, i: int, j: int) -> sp.csr_matrix:
        """Unconstrained stiffness block (3 n_nodes square) coupling active modes ``i`` and ``j``:
        over the elements where their x3 integral is not zero (the cut-outs', for i != j)."""
        I = self._integrals[i, j]
        live = np.flatnonzero(np.abs(I).reshape(len(I), -1).max(axis=1) > 0) if i != j else slice(None)
        Dw = assembly.weighted_elasticity(self.D, I[live])
        p = fourier.wavenumber(self.modes[i], self.body, self.length)
        q = fourier.wavenumber(self.modes[j], self.body, self.length)
        ops = self.ops if i == j else self.ops.subset(live)
        return assembly.assemble(element.element_stiffness(ops, p, Dw, q), self.mesh.elements[live], self.mesh.n_nodes)

    def full_mass(self, i: int, j: int) -> np.ndarray:
        """Unconstrained lumped mass diagonal (3 n_nodes,) of block ``(i, j)``."""
        I = self._integrals[i, j]
        rho_int = self.rho * np.stack([I[:, 0, 0], I[:, 1, 1]], axis=1)
        return assembly.lumped_mass(self.ops.sqrt_g, rho_int, self.mesh.elements, self.mesh.n_nodes)

    @property
    def n_dof(self) -> int:
        return sum(s.T.shape[1] for s in self.systems)

    def harmonics_used(self) -> list[str]:
        return [str(m) for m in self.modes]
