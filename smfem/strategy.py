"""How SMFEM solves a run's steps, decided once, in one table.

Each row is a small class: a condition on the run (:meth:`applies`), a factory of the model and
the system that marches it (:meth:`build`), and the description that names it in
``info['solve']``. The first row whose condition holds is taken (:func:`build_system`):

* elastic, harmonics independent by the case (no contact, the material the same all along x3):
  marched a batch of harmonics at a time, each harmonic factorized apart (:mod:`smfem.batched`;
  :func:`smfem.solver.solve` runs it, :func:`build_system` gives its system of all harmonics);
* ``time_scheme=gauss``: the 2-stage Gauss-Legendre method, the linear system factorized whole;
* a wall or bodies in contact: the contact layer (:mod:`smfem.contact`);
* elastic, modes that do not couple: one block-diagonal factorization;
* elastic, modes coupled by the cut-outs or a material varying along x3: the coupled system
  applied without its matrix and solved by the form of least predicted cost
  (:mod:`smfem.coupled_solve`: whole, Woodbury or conjugate gradients);
* elasto-plastic (or an iteration matrix asked for by name): the additional-loads iterations
  (13)-(16) (:mod:`smfem.iterative`), whose iteration matrix is chosen the same way.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from . import batched, coupled_solve, laws
from .contact import ContactSystem
from .coupling import StackedOperator
from .gauss import GaussSystem
from .iterative import BlockIterative, BlockSOR, ConjugateGradients, Factorized, KRYLOV_MAX, KRYLOV_RTOL
from .stacking import force_terms, stacked
from .model import Model, ModelError
from .newmark import Constants, CoupledLinearSystem, LinearSystem
from .options import SolverOptions

#: iterations per step a plastic run is predicted to take, for the cost of its solves
#: (benchmarks/iterations.py: 1 to 6 on the plastic scenes)
ITERATIONS_PER_STEP = 3
#: relative residual of a linear step solved by conjugate gradients: far below the time error,
#: so the histories are those of a direct solve
LINEAR_KRYLOV_RTOL = 1e-12


@dataclass
class Run:
    """What the choice reads: the case, the options and facts derived from them."""

    case: object
    options: SolverOptions

    @cached_property
    def plastic(self) -> bool:
        """A law whose stress depends on its state: the iterations."""
        return laws.get(self.case.material).nonlinear

    @property
    def scheme(self) -> str:
        return self.case.params.get("time_scheme", "newmark")

    @property
    def contact(self) -> bool:
        return self.case.wall is not None or bool(self.case.contacts)

    @property
    def named_iterations(self) -> bool:
        """An iteration matrix asked for by name that only the iterations have."""
        return self.options.iteration_matrix in ("matrix-free", "sor")

    @cached_property
    def linear_model(self) -> Model:
        """The model of an elastic run: the loaded modes and those the material couples to them."""
        return Model(self.case, bbar=self.options.bbar)

    @property
    def a0(self) -> float:
        return Constants.of(self.case.dt).a0


class Batched:
    """Elastic, the harmonics independent by the case: each factorized apart, marched in batches
    that fit memory."""

    @staticmethod
    def applies(run: Run) -> bool:
        return batched.decoupled(run.case, run.options)

    @staticmethod
    def system(case, model: Model) -> LinearSystem:
        """The linear system of ``model``'s harmonics (a batch's), each factorized apart:
        Newmark's, or with ``time_scheme=gauss`` Gauss's."""
        K, M, Q, _, offsets = stacked(model)
        kind = GaussSystem if case.params.get("time_scheme", "newmark") == "gauss" else LinearSystem
        return kind(K, M, Q, case.dt, force_terms(case, model), blocks=offsets)

    @classmethod
    def build(cls, run: Run):
        model = run.linear_model
        scheme = "the 2-stage Gauss-Legendre method" if run.scheme == "gauss" else "Newmark"
        return model, cls.system(run.case, model), f"decoupled harmonics, each factorized apart ({scheme})"


class GaussScheme:
    """``time_scheme=gauss``: an elastic run without contact, factorized whole."""

    @staticmethod
    def applies(run: Run) -> bool:
        return run.scheme == "gauss"

    @staticmethod
    def build(run: Run):
        case, options = run.case, run.options
        refused = ("plasticity" if run.plastic else "a rigid wall" if case.wall is not None else
                   "contact between bodies" if case.contacts else
                   f"iteration_matrix={options.iteration_matrix}" if options.iteration_matrix not in ("auto", "coupled")
                   else "")
        if refused:
            raise ModelError(f"{case.name}: time_scheme=gauss takes an elastic run without contact, not {refused}: "
                             "set time_scheme=newmark")
        model = run.linear_model
        if model.coupling and model.coupled_nonzeros() > options.direct_max_nonzeros:
            raise ModelError(f"{case.name}: time_scheme=gauss factorizes the coupled system whole, and its "
                             f"{model.coupled_nonzeros()} nonzeros exceed direct_max_nonzeros: set time_scheme=newmark")
        K, M, Q, _, _ = stacked(model)
        how = "the 2-stage Gauss-Legendre method, " + ("the coupled block system" if model.coupling else
                                                       "decoupled harmonics") + ", one complex factorization"
        return model, GaussSystem(K, M, Q, case.dt, force_terms(case, model)), how


class ContactLayer:
    """A rigid wall or bodies in contact: the contact layer, elastic bodies only."""

    @staticmethod
    def applies(run: Run) -> bool:
        return run.contact

    @staticmethod
    def build(run: Run):
        case, options = run.case, run.options
        if run.plastic:
            raise ModelError(f"{case.name}: contact with plasticity is not supported: set plastic=false")
        # harmonic 0 alone for an axisymmetric scene, else every mode the wall's symmetry allows
        model = Model(case, nonlinear=not case.axisymmetric, bbar=options.bbar)
        return model, ContactSystem(model, case.dt, options, force_terms(case, model)), ContactSystem.HOW


class Decoupled:
    """Elastic, the modes independent: one factorization of the block-diagonal system."""

    @staticmethod
    def applies(run: Run) -> bool:
        return not run.plastic and not run.named_iterations and not run.linear_model.coupling

    @staticmethod
    def build(run: Run):
        model = run.linear_model
        K, M, Q, _, _ = stacked(model)
        how = "decoupled harmonics, one block-diagonal factorization"
        return model, LinearSystem(K, M, Q, run.case.dt, force_terms(run.case, model)), how


class CoupledElastic:
    """Elastic, modes coupled along x3: the coupled system applied exactly and solved by the
    form of least predicted cost."""

    DESCRIPTIONS = {
        coupled_solve.Whole.name: "direct: the coupled block system, one factorization",
        coupled_solve.Woodbury.name: "direct: the coupled block system as block-diagonal factors plus the cut-outs' "
                                     "low-rank correction (Woodbury)",
        coupled_solve.Krylov.name: "conjugate gradients on the coupled block system, warm-started, the diagonal "
                                   "blocks as preconditioner",
    }

    @staticmethod
    def applies(run: Run) -> bool:
        return not run.plastic and not run.named_iterations

    @classmethod
    def build(cls, run: Run):
        model, case = run.linear_model, run.case
        form, _ = coupled_solve.choose(model, case.n_steps, run.options.direct_max_nonzeros)
        if run.options.iteration_matrix == "coupled" and form == coupled_solve.Krylov.name:
            form = _cheaper_direct(model, case.n_steps)
        op = StackedOperator(model)
        solver = coupled_solve.build(form, model, run.a0, LINEAR_KRYLOV_RTOL, 10 * KRYLOV_MAX, op)
        Q = np.concatenate([s.Q for s in model.systems])
        system = CoupledLinearSystem(op, solver, model.mass_matrix, Q, case.dt, force_terms(case, model))
        return model, system, f"{cls.DESCRIPTIONS[form]} ({len(model.systems)} harmonics)"


class Iterations:
    """The additional-loads iterations (13)-(16): plastic runs, and any run that names an
    iteration matrix only they have."""

    @staticmethod
    def applies(run: Run) -> bool:
        return True

    @staticmethod
    def build(run: Run):
        case, options = run.case, run.options
        model = Model(case, nonlinear=True, bbar=options.bbar)
        op, a0, n = StackedOperator(model), run.a0, len(model.systems)
        kind = options.iteration_matrix
        if kind in ("auto", "coupled"):
            form, _ = coupled_solve.choose(model, case.n_steps * ITERATIONS_PER_STEP, options.direct_max_nonzeros)
            if form == coupled_solve.Krylov.name and kind == "coupled":
                form = _cheaper_direct(model, case.n_steps * ITERATIONS_PER_STEP)
            kind = "matrix-free" if form == coupled_solve.Krylov.name else "coupled"
        if kind == "coupled":
            iteration = Factorized(coupled_solve.build(form, model, a0))
            how = (f"additional loads (13)-(16), all {n} harmonics in one block-diagonal solve per iteration (they do "
                   "not couple through the stiffness)" if not model.coupling else
                   f"additional loads (13)-(16), the whole coupled elastic system of {n} harmonics as iteration matrix"
                   + (" (block-diagonal plus the cut-outs' low-rank correction, Woodbury)"
                      if form == coupled_solve.Woodbury.name else ""))
        elif kind == "matrix-free":
            iteration = ConjugateGradients(coupled_solve.Krylov(model, a0, KRYLOV_RTOL, KRYLOV_MAX, op))
            how = (f"additional loads (13)-(16), conjugate gradients on the coupled system of {n} harmonics, the "
                   "coupling applied matrix-free through the cut-outs' x3 points, the diagonal blocks as preconditioner")
        else:
            iteration = BlockSOR(model, a0, options.relaxation)
            how = f"block-iterative (13)-(16): block SOR over {n} harmonics, omega {options.relaxation:g}"
        if not isinstance(iteration, BlockSOR) and options.anderson:
            how += f", Anderson acceleration ({options.anderson} iterates)"
        return model, BlockIterative(model, case.dt, options, iteration, op, force_terms(case, model)), how


#: the strategies, in the order they are tried
STRATEGIES = (Batched, GaussScheme, ContactLayer, Decoupled, CoupledElastic, Iterations)


def choose(run: Run):
    """The first strategy that applies to ``run``."""
    return next(s for s in STRATEGIES if s.applies(run))


def build_system(case, options: SolverOptions):
    """The model, the system that solves its steps, and the ``info['solve']`` that names it."""
    run = Run(case, options)
    return choose(run).build(run)


def _cheaper_direct(model, solves: int) -> str:
    """The direct form of least predicted cost, memory aside (``iteration_matrix=coupled``)."""
    costs = coupled_solve.predicted_costs(model)
    return min(costs, key=lambda name: costs[name].total(solves))
