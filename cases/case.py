"""The Case: a frozen, solver-independent description of one verification scene."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .geometry import PRISM, RING, ContactPair, Force, Cutout, Motion, InitialVelocity, Pressure, Probe, Region, Section, Support, Wall
from .material import Material


@dataclass(frozen=True)
class Case:
    """Everything a solver needs, and nothing about how to solve it.

    Attributes
    ----------
    body : ``'ring'`` or ``'prism'`` (see :mod:`cases.geometry` for coordinates)
    section : cross-section block with the paper's mesh counts (before ``refine``)
    material : the material of the section outside ``regions``
    contacts : pairs of faces of two bodies that meet through the contact layer
        (:class:`cases.geometry.ContactPair`; the section then holds several bodies,
        :mod:`cases.bodies`)
    regions : parts of the section of other materials (:class:`cases.geometry.Region`), none
        overlapping; :attr:`materials` and :meth:`material_index` give every element's
    length : prism length along x3 (ring: 2 pi)
    cutouts : regions of absent material; ``contrast`` scales their stiffness and density
    symmetric : ``True`` when loads and material are symmetric about x3 = 0 (ring), so the
        sine family of displacements (u_r, u_z ~ sin) carries nothing
    provenance : which values come from the paper and which are this project's choices
    references : published or analytic reference values with their sources
    source : what :func:`cases.rebuild` builds the case again from: None for a built-in scene
        (its name), a :class:`cases.scene_file.Source` for a scene read from a file; not part of
        the case's equality
    """

    name: str
    title: str
    body: str
    section: Section
    material: Material
    loads: tuple[Pressure, ...]
    supports: tuple[Support, ...]
    probes: tuple[Probe, ...]
    params: dict
    length: float = 2 * math.pi
    cutouts: tuple[Cutout, ...] = ()
    contrast: float = 1.0
    initial_velocity: tuple[InitialVelocity, ...] = ()
    wall: Wall | None = None
    forces: tuple[Force, ...] = ()
    #: the exact motion, when the scene is manufactured to have one
    exact: Motion | None = None
    #: the material varying smoothly along x3: E and rho times ``1 + sum a cos(m k x3)`` over
    #: the terms ``(a, m)`` (k = 1 on a ring, pi / length on a prism), :meth:`variation_factor`
    variation: tuple[tuple[float, int], ...] = ()
    symmetric: bool = True
    axisymmetric: bool = False
    regions: tuple[Region, ...] = ()
    contacts: tuple[ContactPair, ...] = ()
    units: str = "SI (m, N, s, Pa, kg/m^3)"
    provenance: dict = field(default_factory=dict)
    references: dict = field(default_factory=dict)
    source: object = field(default=None, compare=False, repr=False)

    def __post_init__(self):
        if self.body not in (RING, PRISM):
            raise ValueError(f"body must be {RING!r} or {PRISM!r}")
        # the solvers choose their time stepping (linear or the plastic iterations) per case
        if any(r.material.law != self.material.law for r in self.regions):
            raise ValueError(f"{self.name}: every region's material must follow the same law "
                             f"({self.material.law}): all elastic or all plastic")
        surfaces = getattr(self.section, "regions", None) or {}  # a mesh section's physical surfaces
        missing = next((r.name for r in self.regions if r.s_range is None and r.name not in surfaces), None)
        if missing is not None:
            from .params import UnsupportedCase

            raise UnsupportedCase(f"{self.name}: region {missing!r} names a physical surface, which this section "
                                  f"has not (a mapped block has none: give the region s_range and t_range)")
        # what names a region (a body) by the name the section must have
        named = ([(f"an initial velocity is given to region {v.region!r}", v.region) for v in self.initial_velocity]
                 + [(f"probe {p.name!r} averages over region {p.region!r}", p.region) for p in self.probes])
        unknown = next((what for what, region in named if region is not None and region not in surfaces), None)
        if unknown is not None:
            from .params import UnsupportedCase

            raise UnsupportedCase(f"{self.name}: {unknown}, which the section has not (its regions: "
                                  f"{', '.join(surfaces) or 'none'})")
        if self.contacts:
            from .bodies import check_pairs

            check_pairs(self)

    def variation_factor(self, x3):
        """``1 + sum a cos(m k x3)`` at ``x3`` (1 without a variation)."""
        import numpy as np

        k = 1.0 if self.body == RING else math.pi / self.length
        x3 = np.asarray(x3, float)
        return 1.0 + sum(a * np.cos(m * k * x3) for a, m in self.variation) + 0.0 * x3

    @property
    def dt(self) -> float:
        return self.params["dt"]

    @property
    def t_end(self) -> float:
        return self.params["t_end"]

    @property
    def n_steps(self) -> int:
        """Number of time steps: t_end / dt rounded to the nearest integer (at least 1)."""
        return max(1, int(round(self.t_end / self.dt)))

    @property
    def refine(self) -> int:
        return self.params["refine"]

    @property
    def mesh_scale(self) -> float:
        """What the paper mesh's element counts are multiplied by: ``refine / coarsen``."""
        return self.params["refine"] / self.params.get("coarsen", 1)

    @property
    def cutout_edges(self) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """The cut-outs' and the regions' box edges along the section's s and t axes (grid
        nodes at every resolution)."""
        boxes = [*self.cutouts, *(r for r in self.regions if r.s_range is not None)]
        return (tuple(e for c in boxes for e in c.s_range), tuple(e for c in boxes for e in c.t_range))

    @property
    def materials(self) -> tuple:
        """The section's materials: ``material`` (index 0), then each region's."""
        return (self.material,) + tuple(r.material for r in self.regions)

    def material_index(self, st, region_elements: dict | None = None):
        """Index into :attr:`materials` of each element: by the parametric centres ``st`` (n, 2)
        for box regions, by ``region_elements`` (physical surface name -> element ids, a mesh
        section's) for named ones; 0 outside every region."""
        import numpy as np

        index = np.zeros(len(st), int)
        for k, r in enumerate(self.regions, start=1):
            if r.s_range is not None:
                index[r.contains(st[:, 0], st[:, 1])] = k
            else:  # a physical surface the section has (__post_init__)
                index[np.asarray(region_elements[r.name], int)] = k
        return index

    @property
    def harmonics(self) -> int:
        return self.params["harmonics"]

    def unit_of(self, field: str) -> str:
        """The unit of a probe's ``field`` (``'u'``, ``'v'``, ``'sigma'``, ``'peps'``) in the
        case's units: ``'SI ...'`` gives m, m/s, Pa; otherwise the first item of ``units`` is the
        length and the first in parentheses the stress (the dome: ``'in, lbf, s (psi, ...)'``)."""
        if field == "peps":
            return "-"
        if self.units.startswith("SI"):
            length, stress = "m", "Pa"
        else:
            length = self.units.split(",")[0].strip()
            stress = self.units.split("(")[1].split(",")[0].strip() if "(" in self.units else "stress units"
        return {"u": length, "v": f"{length}/s", "sigma": stress}.get(field, "")

    @property
    def probe_names(self) -> list[str]:
        return [p.name for p in self.probes]
