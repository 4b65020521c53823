"""Every solver behind one call: ``solve(solver, case) -> RunResult``.

The names are the ones the studies and ``summary.json`` use: ``smfem``, ``reference-2d``,
``reference-3d`` (the reference FEM with ``dim`` set), ``reference`` (the reference at the
case's own ``dim``), ``reference-modal`` (the reference's harmonic model, exact in time) and
``calculix`` (CalculiX on the reference mesh, at the case's ``dim``; needs ``ccx`` on PATH) and
``reference-explicit`` (the reference's mesh and element, central differences on a lumped
mass at the case's ``dim``: the truth engine of plastic and contact scenes).
Each solver is imported only when it runs, so ``smfem run`` does not load the reference.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable

from cases.result import RunResult

SMFEM, REFERENCE, REF2D, REF3D, MODAL = "smfem", "reference", "reference-2d", "reference-3d", "reference-modal"
CALCULIX, EXPLICIT = "calculix", "reference-explicit"
SOLVERS = (SMFEM, REFERENCE, REF2D, REF3D, MODAL, CALCULIX, EXPLICIT)
#: the ``dim`` each reference name fixes
DIMS = {REF2D: 2, REF3D: 3}


def with_dim(solver: str, case):
    """``case`` with the ``dim`` the solver name fixes (unchanged for the others)."""
    if solver not in DIMS or case.params.get("dim") == DIMS[solver]:
        return case
    from cases import rebuild

    return rebuild(case, {"dim": DIMS[solver]})


def solve(solver: str, case, progress: Callable[[int, int], None] | None = None,
          fields: bool = False, options=None, every: int = 0) -> RunResult:
    """Run ``case`` with ``solver``; ``fields``: keep the synthesized 3-D field of the last
    step in ``result.mesh`` (else None); ``every``: also the field every that many steps in
    ``result.frames`` (SMFEM and the reference FEM); ``options``: SMFEM's
    :class:`smfem.options.SolverOptions` (or a dict of its fields); for the reference FEM a
    dict of keyword arguments of its ``solve`` (``grading``; the explicit one also
    ``step_divisor``)."""
    if solver not in SOLVERS:
        raise ValueError(f"unknown solver {solver!r}: choose one of {', '.join(SOLVERS)}")
    case = with_dim(solver, case)
    if solver in (MODAL, CALCULIX, EXPLICIT) and (case.forces or case.variation):
        from cases import UnsupportedCase

        raise UnsupportedCase(f"{case.name}: body forces and a material varying along x3 are solved by smfem and the "
                              f"reference FEM so far, not by {solver}")
    if solver == SMFEM:
        from smfem.options import SolverOptions
        from smfem.solver import solve as smfem

        options = SolverOptions(**options) if isinstance(options, dict) else options
        return smfem(case, options, progress=progress, with_fields=fields, every=every)
    if solver == MODAL:
        from reference_fem.modal import solve as modal

        return modal(case, progress=progress)
    if solver == CALCULIX:
        from reference_fem.calculix import solve as calculix

        return calculix(case, progress=progress)
    if solver == EXPLICIT:
        from reference_fem.explicit import solve as reference
    else:
        from reference_fem import solve as reference
    result = reference(case, progress=progress, every=every, **(options or {}))
    return result if fields else replace(result, mesh=None)


def family(solver: str) -> str:
    """``smfem``, ``reference``, ``reference-modal``, ``reference-explicit`` or ``calculix``: the
    name a run's ``summary.json`` gives."""
    return REFERENCE if solver in (REF2D, REF3D) else solver
