"""The discrete SMFEM model of a case: mesh, element operators, per-mode matrices and loads.

Built once per case and resolution; time stepping and statics only read it.

A body homogeneous along x3 has decoupled modes: only those that carry a load or an initial
velocity are kept. Where the material varies along x3 (cut-outs) the modes couple through
``D(lm)`` and ``rho(lm)``; then the modes kept are those the loaded ones reach through nonzero
coupling, and ``coupling`` holds the off-diagonal blocks.
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from cases.geometry import RING
from cases.params import UnsupportedCase

from . import (assembly, bbar as projected, constraints, elements, fourier, inhomogeneity, laws, loads,
               mode_blocks, symmetry)
from cases.section_mesh import SectionMesh, section_mesh


#: harmonic pairs assembled per batch by :meth:`Model.coupled_stiffness` (bounds its memory)
CHUNK_PAIRS = 2000


class ModelError(UnsupportedCase):
    """The case asks for something this model cannot represent (a clear, user-facing message)."""


@dataclass
class ModeSystem:
    """One mode: map ``T`` (full <- reduced), diagonal block ``K`` (None where the model keeps
    no stiffness, :class:`Model`), lumped ``M`` diagonal, load
    ``Q`` and initial velocity ``V0`` (reduced); ``Q_terms``: the nodal vector of each of the
    model's timed loads (reduced), which that load's factor for this mode scales."""

    mode: fourier.Mode
    T: sp.csr_matrix
    K: sp.csr_matrix
    M: np.ndarray
    Q: np.ndarray
    V0: np.ndarray
    Q_terms: tuple = ()


class Model:
    """SMFEM model of ``case``.

    Parameters
    ----------
    nonlinear : keep every mode the symmetry of the problem allows (plasticity couples them) and
        set up the x3 sample points for stresses
    element : the section element, a name in :data:`smfem.elements.ELEMENTS`
    bbar : the element's volumetric strain replaced by its projection per element (B-bar,
        :mod:`smfem.bbar`)
    stiffness : keep every mode's reduced stiffness in :attr:`systems` (False: their ``K`` is
        None, assembled for a batch of modes by :meth:`restricted`; a decoupled run marched in
        batches holds one batch's stiffness at a time, :mod:`smfem.batched`)

    The off-diagonal stiffness blocks are assembled only on request
    (:meth:`coupled_stiffness`): a direct solve needs them, the block-iterative solver
    takes the coupling from the stresses instead.
    """

    def __init__(self, case, nonlinear: bool = False, element: str | None = None, bbar: bool = False,
                 stiffness: bool = True):
        self.case = case
        self.body = case.body
        self.length = case.length
        element = element or case.params.get("element", elements.MOMENT4.name)  # the scene's, by default
        self.element = elements.get(element)
        self.mesh: SectionMesh = section_mesh(case.section, case.mesh_scale, case.cutout_edges, self.element.mesh_order)
        if self.mesh.elements.shape[1] != self.element.nodes:
            raise ModelError(f"{case.name}: element {element!r} has {self.element.nodes} nodes, the section mesh's "
                             f"elements {self.mesh.elements.shape[1]}")
        mat = case.material
        #: each element's index into ``case.materials`` (0 everywhere without regions)
        self.material_index = case.material_index(st=self.mesh.element_st_centres(), region_elements=self.mesh.regions)
        #: SMFEM's implementation of the material's law (an unknown one is refused here)
        self.law = laws.get(mat)
        #: the elasticity matrix and density: one (6, 6) and a number on a section of one material,
        #: per element (ne, 6, 6) and (ne,) on one of several (:meth:`element_D`, :meth:`element_rho`)
        self.D = self.law.elastic_matrix()
        self.rho = mat.rho
        nu = mat.nu
        if case.regions:
            self.D = np.stack([laws.get(m).elastic_matrix() for m in case.materials])[self.material_index]
            self.rho = np.array([m.rho for m in case.materials])[self.material_index]
            nu = np.array([m.nu for m in case.materials])[self.material_index][:, None]
        self.ops: elements.Operators = self.element.operators(self.mesh.element_x(), case.body, nu)
        if bbar:
            self.ops = projected.operators(self.element, self.ops)
        self.inhomogeneous = inhomogeneity.varies(case)
        n_harm = case.harmonics
        families = ("c", "s") if case.body == RING else ("p",)
        candidates = fourier.modes(case.body, n_harm, families)
        Q = loads.load_amplitudes(case, self.mesh, candidates)
        V = loads.velocity_amplitudes(case, self.mesh, candidates)
        #: the force terms, then the pressures that vary in time or move (:class:`smfem.loads.TimedLoad`)
        self.timed = loads.timed_loads(case, self.mesh, candidates, self.element)
        times = loads.sample_times(case)
        reach = [term.largest(candidates, times) for term in self.timed]
        size = {m: max([np.abs(Q[m]).max(), np.abs(V[m]).max()] + [r[i] for r in reach])
                for i, m in enumerate(candidates)}
        scale = max(size.values())
        if scale == 0.0:
            raise ModelError(f"{case.name}: no load and no initial velocity: nothing moves")
        loaded = [i for i, m in enumerate(candidates) if size[m] > 1e-12 * scale]
        self.nonlinear = nonlinear
        #: the x3 quadrature of the material's variation, its factor f per element and point, and
        #: the elements where f is not 1 (the only ones that couple harmonics): none where the
        #: body is homogeneous along x3 and the run is linear
        self.x3, self.x3_weights = np.zeros(0), np.zeros(0)
        self.factor = np.ones((self.mesh.n_elements, 0))
        if self.inhomogeneous or nonlinear:
            self.x3, self.x3_weights = inhomogeneity.x3_quadrature(case, n_harm)
            self.factor = inhomogeneity.element_factor(case, self.mesh, self.x3)
        self.cutout_elements = np.flatnonzero((self.factor != 1.0).any(axis=1))
        active = loaded
        if nonlinear:
            allowed = set(symmetry.nonlinear_modes(case, candidates))
            active = [i for i, m in enumerate(candidates) if m in allowed]
        #: the coupling integrals (n_active, n_active, n_profiles, 2, 2) over the elements' few
        #: profiles f(x3) and each element's profile; None where no material varies along x3
        self._I, self._profile = None, None
        #: the pairs of different modes the material couples
        self.coupling: list[tuple[int, int]] = []
        if self.inhomogeneous:
            # elements share a few profiles f(x3) (1 outside the cut-outs): integrate each once
            profiles, self._profile = np.unique(self.factor, axis=0, return_inverse=True)
            self._profile = self._profile.ravel()
            considered = active if nonlinear else list(range(len(candidates)))
            I = inhomogeneity.coupling_integrals([candidates[a] for a in considered], case, profiles,
                                                 self.x3, self.x3_weights)
            # where f = 1 different harmonics are orthogonal along x3: their integrals are
            # round-off; exact zeros keep the coupled matrix sparse
            I[~np.eye(len(considered), dtype=bool)[:, :, None] & (profiles == 1.0).all(axis=1)[None, None, :]] = 0.0
            if not nonlinear:
                # an isotropic D and the lumped mass pair psi1 with psi1 and psi3 with psi3 only
                strength = np.maximum(np.abs(I[..., 0, 0]), np.abs(I[..., 1, 1])).max(axis=2)
                kept = self._reachable(loaded, strength)
                active, I = kept, I[np.ix_(kept, kept)]
            self._I = I
            linked = np.abs(I).reshape(len(active), len(active), -1).max(axis=2) > 0
            np.fill_diagonal(linked, False)
            self.coupling = [tuple(p) for p in np.argwhere(linked).tolist()]
        self.modes = [candidates[a] for a in active]
        fixed = constraints.fixed_dofs(case, self.mesh)
        self.systems: list[ModeSystem] = []
        self._maps = constraints.mode_maps(case, self.mesh, self.modes, fixed)
        #: each mode's :class:`smfem.mode_blocks.SharedBlocks`, or None: assembled by itself
        self._shared = self._shared_blocks() if stiffness else [None] * len(self.modes)
        for i, (mode, T) in enumerate(zip(self.modes, self._maps)):
            K, M = self.reduced_blocks(i) if stiffness else (None, self.reduced_mass(i))
            self.systems.append(ModeSystem(mode, T, K, M, T.T @ Q[mode], self._project(T, V[mode]),
                                           tuple(T.T @ term.shapes[mode] for term in self.timed)))
        self.offsets = np.cumsum([0] + [s.T.shape[1] for s in self.systems])

    def element_D(self, elements=None, spread: int = 0) -> np.ndarray:
        """The elasticity matrix of ``elements`` (all: None), (n, 6, 6) with ``spread`` unit axes
        after the first (to broadcast against per-point arrays), or the section's one (6, 6)."""
        return self.D if self.D.ndim == 2 else _spread(self.D if elements is None else self.D[elements], spread)

    def element_rho(self, elements=None, spread: int = 0):
        """The density of ``elements`` (all: None), (n,) with ``spread`` unit axes after it, or
        the section's one number."""
        return self.rho if np.ndim(self.rho) == 0 else _spread(self.rho if elements is None else self.rho[elements], spread)

    def mass_matrix(self):
        """Stacked mass of all modes: the diagonal (n,) when the modes decouple, else the sparse
        matrix with the mass coupling rho(lm)."""
        diagonal = np.concatenate([s.M for s in self.systems])
        return (sp.diags(diagonal) + self.coupled_mass).tocsr() if self.coupling else diagonal

    def _reduced_maps(self, dofs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per mode, the reduced column of each of ``dofs`` (-1: none) and its coefficient in T:
        two arrays (n_modes, *dofs.shape)."""
        cols, coefs = [], []
        for s in self.systems:
            T = s.T.tocoo()
            r, c = np.full(T.shape[0], -1), np.zeros(T.shape[0])
            r[T.row], c[T.row] = T.col, T.data
            cols.append(r[dofs]), coefs.append(c[dofs])
        return np.stack(cols), np.stack(coefs)

    def _scatter_pairs(self, pairs: np.ndarray, values: np.ndarray, maps) -> tuple:
        """COO entries on the stacked reduced amplitudes of per-pair values on full dofs:
        ``values`` (P, ..., a, b) on rows ``dofs[..., a]`` of mode i and columns ``dofs[..., b]``
        of mode j (``maps``: :meth:`_reduced_maps` of those dofs)."""
        pi, pj = pairs.T
        ri, ci, rj, cj = maps[0][pi], maps[1][pi], maps[0][pj], maps[1][pj]
        keep = (ri[..., :, None] >= 0) & (rj[..., None, :] >= 0) & (values != 0.0)
        at = (slice(None),) + (None,) * ri.ndim  # the pair's offsets against (P, ..., a, b)
        rows = np.broadcast_to(self.offsets[pi][at] + ri[..., :, None], keep.shape)[keep]
        cols = np.broadcast_to(self.offsets[pj][at] + rj[..., None, :], keep.shape)[keep]
        return rows, cols, (values * ci[..., :, None] * cj[..., None, :])[keep]

    def _assemble_pairs(self, blocks, maps) -> sp.csr_matrix:
        """One sparse matrix of per-pair blocks: ``blocks(pairs)`` gives the values of a chunk
        of :attr:`coupling` for :meth:`_scatter_pairs`."""
        n = int(self.offsets[-1])
        pairs = np.array(self.coupling).reshape(-1, 2)
        rows, cols, vals = [], [], []
        for start in range(0, len(pairs), CHUNK_PAIRS):
            chunk = pairs[start:start + CHUNK_PAIRS]
            r, c, v = self._scatter_pairs(chunk, blocks(chunk), maps)
            rows.append(r), cols.append(c), vals.append(v)
        if not rows:
            return sp.csr_matrix((n, n))
        M = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
        M.eliminate_zeros()
        return M

    @cached_property
    def coupled_mass(self) -> sp.csr_matrix:
        """The off-diagonal lumped mass blocks ``rho(lm)`` of every coupled pair, as one matrix:
        a lumped mass is diagonal on the full dofs, so each block maps each cut-out node's dofs,
        which get their share of each of their cut-out elements' ``rho(lm)`` (elsewhere it is 0).
        Built when first asked for (a whole factorization, the initial acceleration under a load):
        every pair of modes has a block at each cut-out dof."""
        if not self.coupling:
            return self._assemble_pairs(None, None)
        live = self.cutout_elements
        nodes, where = np.unique(self.mesh.elements[live], return_inverse=True)
        share = np.zeros((len(nodes), len(live)))
        np.add.at(share, (where.reshape(live.size, -1), np.arange(len(live))[:, None]), self.element_rho(live, 1) * self.ops.node_volume[live])
        dofs = assembly.node_dofs(nodes).reshape(-1, 1)  # (n_dofs, 1): a 1 x 1 block per dof

        def blocks(pairs):
            I = self._I[pairs[:, 0], pairs[:, 1]][:, self._profile[live]]  # (P, ne, 2, 2)
            m = np.stack([I[..., 0, 0] @ share.T, I[..., 1, 1] @ share.T], axis=-1)  # (P, nodes, type)
            return m[:, :, [0, 0, 1]].reshape(len(pairs), -1, 1, 1)  # in-plane as psi1, x3 as psi3

        return self._assemble_pairs(blocks, self._reduced_maps(dofs))

    def coupled_nonzeros(self) -> int:
        """Nonzeros of the whole coupled stiffness, bounded before assembling it: an
        off-diagonal block has at most (element dofs)^2 entries per element where its x3 integral is not
        zero (the cut-outs'), and at most the pattern of its row's diagonal block."""
        diagonal = sum(s.K.nnz for s in self.systems)
        if not self.coupling:
            return diagonal
        n = len(self.systems)
        nonzero = np.abs(self._I).reshape(n, n, self._I.shape[2], -1).max(axis=3) > 0  # (i, j, profile)
        live = nonzero @ np.bincount(self._profile, minlength=self._I.shape[2])  # elements per pair
        pi, pj = np.array(self.coupling).T
        nnz = np.array([s.K.nnz for s in self.systems])
        return int(np.minimum(nnz[pi], self.element.dofs**2 * live[pi, pj]).sum()) + diagonal

    def coupled_stiffness(self) -> sp.csr_matrix:
        """The off-diagonal stiffness blocks ``K(lm)``, l != m, of every coupled pair, as one
        matrix on the stacked reduced amplitudes, assembled over the cut-out elements only
        (elsewhere different harmonics do not couple). With ``B(p) = Ba + p Bb`` at the element's
        sample points (which integrate its stiffness exactly) and
        ``D(lm) = sum_ab I_ab(lm) D_ab``, every element block is a combination of a few fixed
        element matrices, ``K_lm = sum_n c_n(l, m) C_n``: one matrix product per element for
        all pairs."""
        if not self.coupling:
            return self._assemble_pairs(None, None)
        live = self.cutout_elements
        p = np.array([fourier.wavenumber(m, self.body, self.length) for m in self.modes])
        C, terms = assembly.element_terms(self.ops.subset(live), self.element_D(live))
        d = self.element.dofs
        C = C.reshape(len(live), len(terms), d * d)

        def blocks(pairs):
            pi, pj = pairs.T
            I = self._I[pi, pj][:, self._profile[live]]  # (P, ne, 2, 2)
            coef = np.stack([I[:, :, a, b] * (p[pi] ** u * p[pj] ** v)[:, None] for a, b, u, v in terms], axis=-1)
            return (coef.transpose(1, 0, 2) @ C).transpose(1, 0, 2).reshape(len(pairs), len(live), d, d)

        return self._assemble_pairs(blocks, self._reduced_maps(assembly.element_dofs(self.mesh.elements[live])))

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

    def integrals(self, i: int, j: int, homogeneous: bool = False) -> np.ndarray:
        """(n_elements, 2, 2) x3 integrals ``int f psi_a^(i) psi_b^(j)`` of active modes ``i, j``
        per element; ``homogeneous``: with f = 1 everywhere."""
        if self._I is not None and not homogeneous:
            return self._I[i, j][self._profile]
        out = np.zeros((self.mesh.n_elements, 2, 2))
        if i == j:  # homogeneous along x3: exact, and zero between different modes
            out[:, 0, 0], out[:, 1, 1] = fourier.psi_squared_integrals(self.modes[i], self.body, self.length)
        return out

    def _shared_blocks(self) -> list:
        """:attr:`_shared`: the modes of one constraint map (:func:`smfem.constraints.mode_maps`)
        share its :class:`smfem.mode_blocks.SharedBlocks` where that pays
        (:func:`smfem.mode_blocks.pays`); the others are assembled one by one."""
        groups = {}
        for i, T in enumerate(self._maps):
            groups.setdefault(id(T), []).append(i)
        profile = np.zeros(self.mesh.n_elements, int) if self._profile is None else self._profile
        shared, terms = [None] * len(self.modes), None
        for members in groups.values():
            if not mode_blocks.pays(len(members), profile.max() + 1):
                continue
            terms = terms or mode_blocks.terms_by_power(self.ops, self.element_D())
            node_mass = self.element_rho(spread=1) * self.ops.node_volume
            T = self._maps[members[0]]
            blocks = mode_blocks.SharedBlocks(terms, profile, node_mass, self.mesh.elements, T)
            for i in members:
                shared[i] = blocks
        return shared

    def _profile_integrals(self, i: int, homogeneous: bool = False) -> np.ndarray:
        """(profiles, 2, 2) the x3 integrals of active mode ``i`` with itself per profile, or
        (1, 2, 2) those of every element (``homogeneous``: with f = 1 everywhere)."""
        if self._I is not None and not homogeneous:
            return self._I[i, i]
        return np.diag(fourier.psi_squared_integrals(self.modes[i], self.body, self.length))[None]

    def full_stiffness(self, i: int, homogeneous: bool = False) -> sp.csr_matrix:
        """Unconstrained stiffness block (3 n_nodes square) of active mode ``i`` with itself."""
        Dw = assembly.weighted_elasticity(self.D, self.integrals(i, i, homogeneous=homogeneous))
        p = fourier.wavenumber(self.modes[i], self.body, self.length)
        return assembly.assemble(self.ops.stiffness(p, Dw), self.mesh.elements, self.mesh.n_nodes)

    def full_mass(self, i: int, j: int, homogeneous: bool = False) -> np.ndarray:
        """Unconstrained lumped mass diagonal (3 n_nodes,) of block ``(i, j)``."""
        I = self.integrals(i, j, homogeneous=homogeneous)
        rho_int = self.element_rho(spread=1) * np.stack([I[:, 0, 0], I[:, 1, 1]], axis=1)
        return assembly.lumped_mass(self.ops.node_volume, rho_int, self.mesh.elements, self.mesh.n_nodes)

    @cached_property
    def homogeneous_blocks(self) -> list[tuple[sp.csr_matrix, np.ndarray]]:
        """Each mode's reduced stiffness and lumped mass of the body without its cut-outs
        (f = 1), built once: the matrix-free operator and the Woodbury form both start there."""
        return [self.reduced_blocks(i, homogeneous=True) for i in range(len(self.systems))]

    def reduced_blocks(self, i: int, homogeneous: bool = False) -> tuple[sp.csr_matrix, np.ndarray]:
        """Mode ``i``'s reduced stiffness and lumped mass diagonal; ``homogeneous``: of the body
        without its cut-outs (f = 1)."""
        if self._shared[i] is not None:
            p = fourier.wavenumber(self.modes[i], self.body, self.length)
            return self._shared[i].blocks(p, self._profile_integrals(i, homogeneous))
        return self.reduced_stiffness(i, homogeneous), self.reduced_mass(i, homogeneous)

    def reduced_stiffness(self, i: int, homogeneous: bool = False) -> sp.csr_matrix:
        """Mode ``i``'s reduced stiffness assembled by itself (:meth:`reduced_blocks`)."""
        T = self._maps[i]
        return (T.T @ self.full_stiffness(i, homogeneous) @ T).tocsr()

    def reduced_mass(self, i: int, homogeneous: bool = False) -> np.ndarray:
        """Mode ``i``'s reduced lumped mass diagonal by itself (:meth:`reduced_blocks`)."""
        T = self._maps[i]
        return T.multiply(T).T @ self.full_mass(i, i, homogeneous)  # T'diag(m)T: T's columns do not overlap

    def restricted(self, indices, stiffness: bool = True) -> "Model":
        """The model of the decoupled modes ``indices`` (of :attr:`systems`) alone: a shallow copy
        whose systems, modes and offsets are theirs; ``stiffness``: each with its stiffness
        (assembled here where this model keeps none), else as this model keeps them. Probes,
        loads and fields read it as a model of its own: a batch of harmonics marched apart
        (:mod:`smfem.batched`)."""
        if self.coupling:
            raise ValueError("coupled modes cannot be taken apart")
        part = copy.copy(self)
        part._maps = [self._maps[i] for i in indices]
        part._shared = [self._shared[i] for i in indices]
        part.modes = [self.modes[i] for i in indices]
        part.systems = [self.systems[i] if self.systems[i].K is not None or not stiffness else
                        dataclasses.replace(self.systems[i], K=self.reduced_stiffness(i)) for i in indices]
        part.offsets = np.cumsum([0] + [s.T.shape[1] for s in part.systems])
        for cached in ("homogeneous_blocks", "coupled_mass"):  # cached properties of all modes
            part.__dict__.pop(cached, None)
        return part

    @property
    def n_dof(self) -> int:
        return sum(s.T.shape[1] for s in self.systems)

    def harmonics_used(self) -> list[str]:
        return [str(m) for m in self.modes]


def _spread(values: np.ndarray, axes: int) -> np.ndarray:
    """Per-element ``values`` (n, ...) with ``axes`` unit axes inserted after the first."""
    return values.reshape(values.shape[:1] + (1,) * axes + values.shape[1:])
