"""How SMFEM solves, as one explicit record passed into :func:`smfem.solver.solve`.

The defaults are the measured choices (benchmarks/README.md); a study or test that wants
another passes its own :class:`SolverOptions` instead of editing module globals.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SolverOptions:
    """
    Attributes
    ----------
    sweep : how a plastic step's iterations solve for the harmonics: ``'auto'`` solves all of
        them at once with the stacked elastic matrix (block-diagonal for a body homogeneous along
        x3, the whole coupled system where the material varies and it has at most
        ``direct_max_nonzeros`` nonzeros), else the paper's block SOR; ``'sor'``: the paper's
        block SOR over the harmonics always (its iteration counts)
    anderson : iterates an Anderson acceleration of the stacked-solve iterations remembers (0:
        the plain iteration, the paper's)
    relaxation : omega of the block SOR over the harmonics (1: Gauss-Seidel)
    tolerance : relative change of the amplitudes that ends a step's iterations; None takes the
        case's ``tol``
    max_iterations : iterations allowed per step before a run stops as not converged
    direct_max_nonzeros : the largest coupled system (nonzeros of ``K + a0 M``) factorized whole;
        larger ones go through the block-iterative algorithm
    direct : force (True) or forbid (False) the direct coupled solve of an elastic
        inhomogeneous case; None chooses by ``direct_max_nonzeros``
    layer_points_per_harmonic : contact-layer points around the circumference per harmonic kept
        (2 integrate the products of harmonics exactly; the edge of a contact zone needs more,
        benchmarks/README.md)
    max_state_iterations : contact-layer state iterations allowed per step
    """

    sweep: str = "auto"
    anderson: int = 0
    relaxation: float = 1.0
    tolerance: float | None = None
    max_iterations: int = 200
    direct_max_nonzeros: int = 40_000_000
    direct: bool | None = None
    layer_points_per_harmonic: int = 8
    max_state_iterations: int = 60

    def tolerance_for(self, case) -> float:
        return self.tolerance if self.tolerance is not None else case.params["tol"]

    def __post_init__(self):
        if self.sweep not in ("auto", "sor"):
            raise ValueError(f"sweep={self.sweep!r}: 'auto' or 'sor'")
