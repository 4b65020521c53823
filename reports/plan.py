"""What a study runs: per case, series of runs (one per solver) over resolution levels.

A level is a dict of ``--set`` overrides (``refine``, ``harmonics``, ``dt``); every run of a
case also gets the case study's ``base`` overrides (a shorter window for a tiny study, say).
The error reference of a case is one extra run, finer than any level of its series, unless an
analytic history exists (:mod:`reports.references`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from cases import ParameterError

SMFEM, REF2D, REF3D = "smfem", "reference-2d", "reference-3d"
SOLVERS = (SMFEM, REF2D, REF3D)
#: the ``--set`` keys that make a level; the one with most distinct values along a series is its h
RESOLUTION_KEYS = ("refine", "harmonics", "dt")


@dataclass(frozen=True)
class Series:
    """Runs of one solver over levels, coarse to fine."""

    solver: str
    levels: tuple[dict, ...]

    def __post_init__(self):
        if self.solver not in SOLVERS:
            raise ValueError(f"solver must be one of {SOLVERS}, not {self.solver!r}")


@dataclass(frozen=True)
class CaseStudy:
    """The runs that measure one case: series per solver and the finest reference-FEM run.

    The SMFEM run at the case's own settings (no level overrides) also writes ``fields.vtu``
    and plastic zones, for the 3-D view.
    """

    case: str
    series: tuple[Series, ...]
    reference: tuple[str, dict]
    base: dict = field(default_factory=dict)


def _s(solver, *levels):
    return Series(solver, tuple(levels))


def quick() -> tuple[CaseStudy, ...]:
    """The default report: every case at the paper's time step, meshes up to a few times the
    paper's, so the whole study runs in a few minutes on two cores.

    The time step stays the paper's in every run (CASES.md: solver-to-solver differences are
    spatial), so errors measure the spatial discretization only.
    """
    return (
        CaseStudy("dome", (
            _s(SMFEM, {"refine": 1}, {"refine": 2}, {"refine": 4}, {"refine": 8}),
            _s(REF2D, {"refine": 1}, {"refine": 2}, {"refine": 4}),
            _s(REF3D, {"refine": 1}),
        ), reference=(REF2D, {"refine": 8})),
        CaseStudy("thick_cylinder", (
            _s(SMFEM, {"harmonics": 10}, {"harmonics": 20}, {"refine": 2, "harmonics": 40},
               {"refine": 4, "harmonics": 80}),
            _s(REF2D, {"refine": 1}, {"refine": 2}),
            _s(REF3D, {"refine": 1}),
        ), reference=(REF2D, {"refine": 3})),
        CaseStudy("notched_cylinder", (
            _s(SMFEM, {"harmonics": 10}, {"harmonics": 20}, {"harmonics": 40}),
            _s(REF2D, {"refine": 1}),
            _s(REF3D, {"refine": 1}),
        ), reference=(REF2D, {"refine": 2})),
        CaseStudy("notched_strip", (
            _s(SMFEM, {"harmonics": 20}, {"harmonics": 40}, {"harmonics": 80}),
            _s(REF2D, {"refine": 1}),
            _s(REF3D, {"refine": 1}),
        ), reference=(REF2D, {"refine": 2})),
        CaseStudy("rod_impact", (
            _s(SMFEM, {"refine": 1}, {"refine": 2}, {"refine": 4}),
            _s(REF2D, {"refine": 1}, {"refine": 2}),
            _s(REF3D, {"refine": 1}),
        ), reference=(REF2D, {"refine": 4})),
    )


def full() -> tuple[CaseStudy, ...]:
    """The larger study: finer levels, 3-D at two meshes where affordable, a finer reference."""
    return (
        CaseStudy("dome", (
            _s(SMFEM, {"refine": 1}, {"refine": 2}, {"refine": 4}, {"refine": 8}, {"refine": 16}),
            _s(REF2D, {"refine": 1}, {"refine": 2}, {"refine": 4}, {"refine": 8}),
            _s(REF3D, {"refine": 1}, {"refine": 2}),
        ), reference=(REF2D, {"refine": 16})),
        CaseStudy("thick_cylinder", (
            _s(SMFEM, {"harmonics": 10}, {"harmonics": 20}, {"refine": 2, "harmonics": 40},
               {"refine": 4, "harmonics": 80}, {"refine": 8, "harmonics": 80}),
            _s(REF2D, {"refine": 1}, {"refine": 2}, {"refine": 3}),
            _s(REF3D, {"refine": 1}, {"refine": 2}),
        ), reference=(REF2D, {"refine": 4})),
        CaseStudy("notched_cylinder", (
            _s(SMFEM, {"harmonics": 10}, {"harmonics": 20}, {"harmonics": 40}, {"refine": 2, "harmonics": 40}),
            _s(REF2D, {"refine": 1}, {"refine": 2}),
            _s(REF3D, {"refine": 1}),
        ), reference=(REF2D, {"refine": 3})),
        CaseStudy("notched_strip", (
            _s(SMFEM, {"harmonics": 20}, {"harmonics": 40}, {"harmonics": 80}, {"harmonics": 120}),
            _s(REF2D, {"refine": 1}, {"refine": 2}),
            _s(REF3D, {"refine": 1}, {"refine": 2}),
        ), reference=(REF2D, {"refine": 3})),
        CaseStudy("rod_impact", (
            _s(SMFEM, {"refine": 1}, {"refine": 2}, {"refine": 4}),
            _s(REF2D, {"refine": 1}, {"refine": 2}, {"refine": 4}),
            _s(REF3D, {"refine": 1}),
        ), reference=(REF2D, {"refine": 8})),
    )


def select(plan: tuple[CaseStudy, ...], names) -> tuple[CaseStudy, ...]:
    """The case studies of ``names`` (all when empty), in the order given."""
    if not names:
        return plan
    by_name = {s.case: s for s in plan}
    unknown = [n for n in names if n not in by_name]
    if unknown:
        raise ParameterError(f"unknown case {unknown[0]!r}: choose one of {', '.join(by_name)}")
    return tuple(by_name[n] for n in names)
