"""Per-mode constraints: supports, components a mode does not carry, and regularity on the axis.

Each mode gets a sparse map ``T`` (n_full, n_free) with ``u_full = T u_free``. Axis nodes of a
ring (r = 0) follow the regularity of each harmonic (docs/method.md): l = 0: u_r = u_theta = 0;
l = 1: u_z = 0 and u_theta = -u_r (a lateral translation of the axis point); l >= 2: all zero.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from cases.geometry import RING

from .fourier import Mode, absent_components
from cases.section_mesh import SectionMesh


def fixed_dofs(case, mesh: SectionMesh) -> np.ndarray:
    """Dofs zeroed by the case's supports (all modes alike)."""
    fixed = []
    for sup in case.supports:
        nodes = np.arange(mesh.n_nodes) if sup.edge == "all" else mesh.edge_nodes(sup.edge)
        fixed += [3 * nodes + (c - 1) for c in sup.components]
    return np.unique(np.concatenate(fixed)) if fixed else np.array([], int)


def mode_maps(case, mesh: SectionMesh, modes: list[Mode], fixed: np.ndarray) -> list[sp.csr_matrix]:
    """The map of each of ``modes`` (:func:`mode_map`); modes with the same absent components and
    regularity on the axis share one."""
    def read(mode):  # what mode_map reads of a mode
        return absent_components(mode), min(mode.l, 2) if case.body == RING else 0

    maps = {}
    for mode in modes:
        if read(mode) not in maps:
            maps[read(mode)] = mode_map(case, mesh, mode, fixed)
    return [maps[read(mode)] for mode in modes]


def mode_map(case, mesh: SectionMesh, mode: Mode, fixed: np.ndarray) -> sp.csr_matrix:
    """The map ``T`` (n_full, n_free) of one mode."""
    n_full = 3 * mesh.n_nodes
    free = np.ones(n_full, bool)
    free[fixed] = False
    for c in absent_components(mode):
        free[c::3] = False
    tie_from, tie_to = np.array([], int), np.array([], int)
    if case.body == RING:
        axis = mesh.axis_nodes()
        if mode.l == 0:
            free[3 * axis] = free[3 * axis + 2] = False
        elif mode.l == 1:
            free[3 * axis + 1] = False
            both = free[3 * axis] & free[3 * axis + 2]
            tie_from, tie_to = 3 * axis[both], 3 * axis[both] + 2  # u_theta follows -u_r
            free[3 * axis + 2] = False
        else:
            free[3 * axis] = free[3 * axis + 1] = free[3 * axis + 2] = False
    idx = np.flatnonzero(free)
    col = np.full(n_full, -1)
    col[idx] = np.arange(len(idx))
    rows = np.concatenate([idx, tie_to])
    cols = np.concatenate([np.arange(len(idx)), col[tie_from]])
    vals = np.concatenate([np.ones(len(idx)), -np.ones(len(tie_to))])
    return sp.csr_matrix((vals, (rows, cols)), shape=(n_full, len(idx)))
