"""The record every solver returns (data, like the rest of this package: no numerics).

SMFEM, the reference FEM and the reference's modal solution all return a :class:`RunResult`;
``runs/`` writes it to files (docs/contract.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import meshio
import numpy as np


#: the equivalent plastic strain that counts as plastic in a zone's area
ZONE_THRESHOLD = 1e-3


@dataclass
class ZoneSnapshot:
    """The equivalent plastic strain at one time, cell by cell in the plane both solvers draw
    in (the x-y plane of a ring, the (r, z) half-plane of an axisymmetric ring, the (span,
    height) plane of a prism).

    Attributes
    ----------
    t : time, s
    poly : (n, 4, 2) cell corners
    peps : (n,) cell means
    peak : the largest point value (what the ``peps_max`` probe gives; a cell's mean stays below it)
    solid : (n,) False where the cell lies in a cut-out (SMFEM's fictitious material); None: all solid
    """

    t: float
    poly: np.ndarray
    peps: np.ndarray
    peak: float
    solid: np.ndarray | None = None

    @property
    def solid_cells(self) -> np.ndarray:
        return np.ones(len(self.peps), bool) if self.solid is None else self.solid


@dataclass
class RunResult:
    """Histories and facts of one run.

    Attributes
    ----------
    t : (n_steps + 1,) times including t = 0, s
    history : probe name -> (n_steps + 1,) values
    n_dof : unknowns actually solved for
    iterations : per step (1 for a linear step)
    converged : False if a step failed; ``message`` then names the step and time
    cpu_time_s : process CPU time of the solve (model building and time stepping), s
    mesh : synthesized 3-D field at the last computed step, or None
    info : solver-specific facts (``harmonics_used``, factorizations, ...; each solver's
        ``solve`` lists its own)
    snapshots : :class:`ZoneSnapshot` at the case's plastic-zone times
    frames : ``(t, mesh)`` of the field every N steps, t = 0 included, when a time series was
        asked for (``--every N``); else empty
    """

    t: np.ndarray
    history: dict[str, np.ndarray]
    n_dof: int
    iterations: list[int]
    converged: bool = True
    message: str = ""
    cpu_time_s: float = 0.0
    mesh: meshio.Mesh | None = None
    info: dict = field(default_factory=dict)
    snapshots: list = field(default_factory=list)
    frames: list = field(default_factory=list)
