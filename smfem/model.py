"""The discrete SMFEM model of a case: mesh, element operators, per-mode matrices and loads.

Built once per case and resolution; time stepping and statics only read it. For a body that is
homogeneous along x3 the modes decouple, and only modes that carry a load or an initial
velocity are kept (``modes``); ``candidates`` are all the modes the harmonics allow.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from cases.geometry import RING

from . import assembly, constraints, element, fourier, loads
from .constitutive import isotropic_D
from .mesh import SectionMesh, section_mesh


class ModelError(ValueError):
    """The case asks for something this model cannot represent (a clear, user-facing message)."""


@dataclass
class ModeSystem:
    """Reduced matrices of one decoupled mode: ``K``, lumped ``M`` diagonal, load ``Q``, map ``T``."""

    mode: fourier.Mode
    T: sp.csr_matrix
    K: sp.csr_matrix
    M: np.ndarray
    Q: np.ndarray
    V0: np.ndarray


class Model:
    """SMFEM model of ``case`` (homogeneous along x3: decoupled modes)."""

    def __init__(self, case, refine: int | None = None, harmonics: int | None = None, scheme: str = "moment"):
        if case.cutouts and case.contrast < 1.0:
            raise ModelError(
                f"{case.name}: material varying along x3 (cut-outs) couples the harmonics; "
                "the coupled solver is not part of this version"
            )
        self.case = case
        self.body = case.body
        self.length = case.length
        self.scheme = scheme
        self.mesh: SectionMesh = section_mesh(case.section, refine or case.refine)
        X = self.mesh.element_x()
        self.ops = element.operators(X, case.body)
        mat = case.material
        self.D = isotropic_D(mat.E, mat.nu)
        self.rho = mat.rho
        families = ("c", "s") if case.body == RING else ("p",)
        self.candidates = fourier.modes(case.body, harmonics or case.harmonics, families)
        Q = loads.load_amplitudes(case, self.mesh, self.candidates)
        V = loads.velocity_amplitudes(case, self.mesh, self.candidates)
        scale = max([np.abs(q).max() for q in Q.values()] + [np.abs(v).max() for v in V.values()] + [0.0])
        if scale == 0.0:
            raise ModelError(f"{case.name}: no load and no initial velocity: nothing moves")
        active = [m for m in self.candidates if max(np.abs(Q[m]).max(), np.abs(V[m]).max()) > 1e-12 * scale]
        fixed = constraints.fixed_dofs(case, self.mesh)
        self.systems = []
        for mode in active:
            T = constraints.mode_map(case, self.mesh, mode, fixed)
            if T.shape[1] == 0:
                continue
            K = (T.T @ self.full_stiffness(mode) @ T).tocsr()
            M = T.multiply(T).T @ self.full_mass(mode)  # T'diag(m)T stays diagonal: T's columns do not overlap
            self.systems.append(ModeSystem(mode, T, K, M, T.T @ Q[mode], self._project(T, V[mode])))
        self.modes = [s.mode for s in self.systems]

    @staticmethod
    def _project(T: sp.csr_matrix, v: np.ndarray) -> np.ndarray:
        """Reduced coordinates of a full vector that lies in the range of ``T``."""
        return sp.linalg.lsqr(T, v, atol=1e-14, btol=1e-14)[0] if v.any() else np.zeros(T.shape[1])

    def integrals(self, mode: fourier.Mode) -> np.ndarray:
        """(n_elements, 2, 2) x3 integrals of basis products for a homogeneous body."""
        i1, i3 = fourier.psi_squared_integrals(mode, self.body, self.length)
        out = np.zeros((self.mesh.n_elements, 2, 2))
        out[:, 0, 0], out[:, 1, 1] = i1, i3
        return out

    def full_stiffness(self, mode: fourier.Mode) -> sp.csr_matrix:
        """Unconstrained stiffness (3 n_nodes square) of one mode."""
        Dw = assembly.weighted_elasticity(self.D, self.integrals(mode))
        p = fourier.wavenumber(mode, self.body, self.length)
        if self.scheme == "moment":
            blocks = element.element_stiffness(self.ops, p, Dw)
        elif self.scheme == "full":
            blocks = element.element_stiffness_full(self.mesh.element_x(), self.body, p, Dw)
        else:
            raise ModelError(f"unknown element scheme {self.scheme!r}: 'moment' or 'full'")
        return assembly.assemble(blocks, self.mesh.elements, self.mesh.n_nodes)

    def full_mass(self, mode: fourier.Mode) -> np.ndarray:
        """Unconstrained lumped mass diagonal (3 n_nodes,) of one mode."""
        I = self.integrals(mode)
        rho_int = self.rho * np.stack([I[:, 0, 0], I[:, 1, 1]], axis=1)
        return assembly.lumped_mass(self.ops.sqrt_g, rho_int, self.mesh.elements, self.mesh.n_nodes)

    @property
    def n_dof(self) -> int:
        return sum(s.T.shape[1] for s in self.systems)

    def harmonics_used(self) -> list[str]:
        return [str(m) for m in self.modes]
