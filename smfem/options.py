"""How SMFEM solves, as one explicit record passed into :func:`smfem.solver.solve`.

The defaults are the measured choices (benchmarks/README.md); a study or test that wants
another passes its own :class:`SolverOptions` instead of editing module globals, and the
command line takes each field as ``--set FIELD=VALUE``. The iterations' tolerance is not one of
them: it is the case's ``tol`` (the scenes give the paper's), in one place; so is the section
element, the case's ``element``.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from cases.params import Spec

#: what each field accepts, checked as case parameters are (``--set``: one line, exit 2); every
#: bound finite, so that no setting runs away (an Anderson memory of 10^9 iterates, a floor of
#: 10^12 stress points)
SPECS = {
    "iteration_matrix": Spec(str, choices=("auto", "coupled", "matrix-free", "sor"),
                             help="what a nonlinear step's iterations solve with"),
    "anderson": Spec(int, 0, 100, help="iterates Anderson acceleration remembers (0: the plain iteration)"),
    # block SOR converges for omega in (0, 2) only (Ostrowski-Reich)
    "relaxation": Spec(float, 0.0, 2.0, open_lo=True, open_hi=True, help="omega of the block SOR"),
    "max_iterations": Spec(int, 1, 100_000, help="iterations allowed per step"),
    "direct_max_nonzeros": Spec(int, 0, 10**12, help="largest coupled system factorized whole"),
    # None (the default): the measured multiple; fewer than the exact count would not be exact
    "x3_oversampling": Spec(float, 1.0, 64.0, help="stress points along x3, in multiples of the exact count"),
    "x3_min_points": Spec(int, 0, 100_000, help="fewest stress points along x3 (0: no floor)"),
    "layer_points_per_harmonic": Spec(int, 1, 1000, help="contact-layer points per harmonic"),
    "max_state_iterations": Spec(int, 1, 100_000, help="contact-layer state iterations allowed per step"),
    "bbar": Spec(bool, help="the section element's volumetric strain projected per element (B-bar)"),
    "batch_memory_mb": Spec(float, 0.0, 1e7, open_lo=True,
                            help="memory a batch of decoupled harmonics may take, MB (predicted)"),
}


@dataclass(frozen=True)
class SolverOptions:
    """
    Attributes
    ----------
    iteration_matrix : what a nonlinear step's iterations solve with (the residual is always the
        exact one, the harmonic coupling included): ``'coupled'``, the whole coupled elastic
        ``K + a0 M`` factorized once; ``'matrix-free'``, that system solved by conjugate gradients
        with the coupling applied through the cut-outs' x3 points and the per-harmonic diagonal
        blocks, factorized, as preconditioner (memory grows linearly with the harmonics);
        ``'sor'``, the paper's block SOR over the harmonics; ``'auto'``: the direct form of
        least predicted cost that fits in memory (:mod:`smfem.coupled_solve`: block-diagonal,
        the whole coupled matrix within ``direct_max_nonzeros``, or block-diagonal plus the
        cut-outs' low-rank correction), else ``'matrix-free'``. An elastic body with cut-outs is
        solved by that form (one solve per step) under ``'auto'`` and ``'coupled'``, by the
        iterations otherwise.
    anderson : iterates an Anderson acceleration of the iterations remembers (0: the plain
        iteration, the paper's; not with ``'sor'``)
    relaxation : omega of the block SOR over the harmonics (1: Gauss-Seidel)
    max_iterations : iterations allowed per step before a run stops as not converged
    direct_max_nonzeros : the largest coupled system (nonzeros of ``K + a0 M``) factorized whole
        under ``'auto'`` (the cost decides below it)
    x3_oversampling : stress sample points along x3, in multiples of the fewest that integrate
        the kept modes exactly (:mod:`smfem.sampling`); None: the multiple measured for the scene
        and harmonic count (:mod:`cases.x3_points`: the plastic-zone area within 1 % of twice
        as many points), else 1
    x3_min_points : the fewest stress points along x3 over the modes' fundamental domain, on
        top of that (0: no floor)
    layer_points_per_harmonic : contact-layer points around the circumference per harmonic kept
        (2 integrate the products of harmonics exactly; the edge of a contact zone needs more,
        benchmarks/README.md)
    max_state_iterations : contact-layer state iterations allowed per step
    bbar : the section element's volumetric strain of each harmonic replaced by its projection
        per element (B-bar, :mod:`smfem.bbar`: the element mean on the moment-scheme
        quadrilateral, ``{1, xi, eta}`` on the 9-node one), in the stiffness and at the stress
        sample points alike; against volumetric locking in plastic flow
    batch_memory_mb : the memory a batch of decoupled harmonics may take, MB, as predicted
        before it is built (:mod:`smfem.batched`: a linear run whose harmonics do not couple
        marches them in batches); never more than half the memory the machine has available;
        a batch takes one harmonic at least. Larger batches march no faster (measured in
        benchmarks/README.md), so the default keeps them small
    """

    iteration_matrix: str = "auto"
    anderson: int = 5
    relaxation: float = 1.0
    max_iterations: int = 200
    direct_max_nonzeros: int = 40_000_000
    x3_oversampling: float | None = None
    x3_min_points: int = 0
    layer_points_per_harmonic: int = 8
    max_state_iterations: int = 60
    bbar: bool = False
    batch_memory_mb: float = 16.0

    def __post_init__(self):
        """Every field checked by its :data:`SPECS` (a :class:`cases.ParameterError`, one line)
        and stored as its type (``--set anderson=3.0`` is the integer 3)."""
        for f in fields(self):
            value = getattr(self, f.name)
            if not (f.name == "x3_oversampling" and value is None):
                object.__setattr__(self, f.name, SPECS[f.name].check(f.name, value))
