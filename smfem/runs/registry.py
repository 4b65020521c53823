"""Every solver behind one call, ``solve(solver, case) -> RunResult``, and the one table that
declares them: a :class:`Solver` entry per name holds how it runs and everything the other
layers ask about it (the ``dim`` it fixes, the packages that key its cached runs, what it can
run, how the report draws it). Adding a solver is one :func:`register` call.

The names are the ones the studies and ``summary.json`` use: ``smfem``, ``reference-2d``,
``smfem-quad9`` (SMFEM with its quadratic section element, ``element=quad9``),
``reference-3d`` (the reference FEM with ``dim`` set), ``reference`` (the reference at the
case's own ``dim``), ``reference-modal`` (the reference's harmonic model, exact in time) and
``calculix`` (CalculiX on the reference mesh, at the case's ``dim``; needs ``ccx`` on PATH;
its implicit procedure unless told otherwise), ``calculix-explicit`` and ``calculix-modal``
(CalculiX with its procedure fixed: a study's series each, one row of the headline),
``reference-explicit`` (the reference's mesh and element, central differences on a lumped
mass at the case's ``dim``: the truth engine of plastic and contact scenes) and
``reference-3d-explicit`` (that engine with ``dim`` 3: a study's series, in the headline's
``reference-3d`` row, whose cells name the cheaper of the 3D reference's two engines).
Each solver is imported only when it runs, so ``smfem run`` does not load the reference.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import partial
from typing import Callable

from cases.params import ParameterError, Spec
from cases.result import RunResult

SMFEM, REFERENCE, REF2D, REF3D, MODAL = "smfem", "reference", "reference-2d", "reference-3d", "reference-modal"
CALCULIX, EXPLICIT = "calculix", "reference-explicit"
#: CalculiX with its ``procedure`` fixed (:attr:`Solver.options_fixed`): a study's series of their own
CALCULIX_EXPLICIT, CALCULIX_MODAL = "calculix-explicit", "calculix-modal"
#: the explicit reference in 3D: a study's series of its own, one headline row with ``reference-3d``
REF3D_EXPLICIT = "reference-3d-explicit"
#: SMFEM with the 9-node section element (:mod:`smfem.quad9`): a study's series of its own
SMFEM_QUAD9 = "smfem-quad9"

#: what a solver can run (:attr:`Solver.supports`): the synthesized 3-D field of the last step
#: (``fields``), that field every N steps (``frames``, a time series), plasticity, a rigid wall
#: (``contact``), and body forces, tractions and a material varying along x3 (``forces``)
FIELDS, FRAMES, PLASTICITY, CONTACT, FORCES = "fields", "frames", "plasticity", "contact", "forces"
EVERYTHING = frozenset((FIELDS, FRAMES, PLASTICITY, CONTACT, FORCES))


def _anywhere() -> bool:
    """A solver that runs no external program is installed wherever smfem is."""
    return True


@dataclass(frozen=True)
class Solver:
    """One entry of the solver table.

    Parameters
    ----------
    name : what studies, the cache and the command line call it
    run : ``run(case, progress=, fields=, every=, options=) -> RunResult``; imports its solver
        when called, and must be importable by name (a module-level function) where a study's
        workers run it
    family : the name ``summary.json`` gives (default ``name``)
    dim : the reference ``dim`` the name fixes (None: the case's own)
    fixes : other case parameters the name fixes, ``(key, value)`` pairs (SMFEM's quadratic
        element: ``(("element", "quad9"),)``): a series of its own in a study, with the same
        numerics as its family's entry
    options_fixed : solver options the name fixes, ``(key, value)`` pairs (CalculiX's
        ``procedure``): a series of its own in a study, and one row with its family's in the
        report's headline (:func:`headline_name`), where a cell names its :attr:`variant`
    variant : the word that tells it from the other entries in a headline row they share
        (default: the values of :attr:`options_fixed`)
    headline : the row of the report's headline its series count in, at each target the
        cheapest of the row's series (default: its family's for an entry that fixes only solver
        options, CalculiX's procedures; its own name otherwise). The explicit 3D reference
        counts in ``reference-3d``'s
    packages : the packages whose sources decide its results besides ``cases`` and ``runs``
        (a change to them reruns its cached runs, :func:`smfem.studies.cache.code_version`)
    supports : of :data:`EVERYTHING`. :func:`solve` refuses ``forces`` where it is missing (the
        solver would ignore them); plasticity and contact each solver refuses itself, with its
        own reason (``tests/test_registry.py`` holds the table to it)
    label, color, marker : its name in a figure and how its points are drawn
    prose : how a sentence of the report names it (default ``label``)
    harmonics : its discretization has a number of harmonics (shown in a run's label; the
        error estimate halves it)
    estimated : a run's error estimate is made from its companions (:mod:`smfem.runs.estimate`): a
        time-stepping solver on a mesh that ``refine`` and ``coarsen`` set
    courant : its time step is its own Courant limit, which shrinks with the mesh's elements
        (explicit dynamics): a run's work grows by one more power of ``refine`` than its
        unknowns' (:func:`smfem.studies.ladder.work`)
    command_line : offered by ``smfem run --solver``
    series : a study may run a series of it (not: the truth engines, and ``reference``,
        whose ``dim`` a study fixes by name)
    dear : its runs are a study's longest (3-D, an external program): started first
    options : ``options() -> dict``, its own options (``solve``'s ``options``) by name, each with
        the :class:`cases.params.Spec` that checks it: ``smfem run --set`` passes them to it
        rather than to the case (a function: the solver's options module is imported only when
        asked)
    make_options : ``make_options(dict)``: the options ``run`` takes, checked (a ValueError or
        TypeError names a bad one)
    checks : ``checks() -> dict``: the solver's own numerical checks by name (the stability
        study's: ``static_probes(case)``, and SMFEM's ``explicit_limit``, ``free_vibration``,
        ``stiffness_condition``), imported only when asked
    installed : ``installed() -> bool``: the external program it runs is on this machine (a plan
        leaves out what cannot run here)
    """

    name: str
    run: Callable[..., RunResult]
    family: str = ""
    dim: int | None = None
    fixes: tuple = ()
    options_fixed: tuple = ()
    variant: str = ""
    headline: str = ""
    packages: tuple[str, ...] = ("reference_fem",)
    supports: frozenset = EVERYTHING
    label: str = ""
    color: str = "0.45"
    marker: str = "x"
    prose: str = ""
    harmonics: bool = False
    estimated: bool = False
    courant: bool = False
    command_line: bool = True
    series: bool = True
    dear: bool = False
    options: Callable[[], dict] = dict
    make_options: Callable[[dict], object] = dict
    checks: Callable[[], dict] = dict
    installed: Callable[[], bool] = _anywhere

    def __post_init__(self):
        if not self.supports <= EVERYTHING:
            unknown = sorted(self.supports - EVERYTHING)
            raise ValueError(f"{self.name}: supports {unknown}: not one of {sorted(EVERYTHING)}")
        # defaults that depend on other fields (frozen: set once, here)
        object.__setattr__(self, "family", self.family or self.name)
        object.__setattr__(self, "label", self.label or self.name)
        object.__setattr__(self, "prose", self.prose or self.label)
        object.__setattr__(self, "variant", self.variant or " ".join(str(v) for _, v in self.options_fixed))
        shares = self.options_fixed and not self.fixed  # one solver's procedures: its family's row
        object.__setattr__(self, "headline", self.headline or (self.family if shares else self.name))

    @property
    def fixed(self) -> dict:
        """The case parameters the name fixes (``dim`` and :attr:`fixes`)."""
        return ({} if self.dim is None else {"dim": self.dim}) | dict(self.fixes)

    @property
    def fixed_options(self) -> dict:
        """The solver options the name fixes (:attr:`options_fixed`)."""
        return dict(self.options_fixed)

    @property
    def style(self) -> dict:
        """matplotlib's keyword arguments of its points."""
        return {"color": self.color, "marker": self.marker}


_TABLE: dict[str, Solver] = {}


def register(entry: Solver) -> Solver:
    """Add ``entry`` to the table (a name already there is an error)."""
    if entry.name in _TABLE:
        raise ValueError(f"solver {entry.name!r} is registered already")
    _TABLE[entry.name] = entry
    return entry


def unregister(name: str) -> None:
    """Take ``name`` out of the table (a test's solver, after the test)."""
    del _TABLE[lookup(name).name]


def lookup(name: str) -> Solver:
    """The entry of ``name``; a ValueError naming the registered solvers otherwise."""
    try:
        return _TABLE[name]
    except KeyError:
        raise ValueError(f"unknown solver {name!r}: choose one of {', '.join(_TABLE)}") from None


def solvers() -> tuple[Solver, ...]:
    """Every entry, in the order registered (the order of a report's rows and legends)."""
    return tuple(_TABLE.values())


def _entry(solver: str | Solver) -> Solver:
    return solver if isinstance(solver, Solver) else lookup(solver)


def with_fixed(solver: str | Solver, case):
    """``case`` with the parameters the solver fixes (:attr:`Solver.fixed`; unchanged where it
    fixes none or the case has them)."""
    fixed = _entry(solver).fixed
    if all(case.params.get(k) == v for k, v in fixed.items()):
        return case
    from cases import rebuild

    return rebuild(case, fixed)


def named_for(solver: str, case) -> str:
    """The name of the entry that runs ``case`` as ``solver`` does with its parameters fixed
    (``reference`` at dim 3: ``reference-3d``; ``smfem`` with ``element=quad9``: ``smfem-quad9``;
    ``solver`` where no entry of its family fixes them)."""
    entry = lookup(solver)
    if entry.fixed:
        return entry.name
    params = {"dim": 2} | case.params
    return next((s.name for s in _TABLE.values() if s.family == entry.family and s.fixed
                 and all(params.get(k) == v for k, v in s.fixed.items())), entry.name)


def split_level(solver: str | Solver, level: dict) -> tuple[dict, dict]:
    """A study level's case overrides and the solver's own options (the keys its
    :attr:`Solver.options` name: CalculiX's ``modes``), apart."""
    own = _entry(solver).options()
    return ({k: v for k, v in level.items() if k not in own}, {k: v for k, v in level.items() if k in own})


def headline_name(solver: str) -> str:
    """The row of the report's headline a solver's series counts in (:attr:`Solver.headline`):
    CalculiX's procedures one row, the 3D reference's implicit and explicit engines one row
    (one competitor each, at its cheapest), SMFEM's elements and the 2D reference rows of their
    own."""
    return lookup(solver).headline


def checks(solver: str | Solver) -> dict:
    """The solver's own numerical checks by name (:attr:`Solver.checks`)."""
    return _entry(solver).checks()


def family(solver: str) -> str:
    """``smfem``, ``reference``, ``reference-modal``, ``reference-explicit`` or ``calculix``: the
    name a run's ``summary.json`` gives."""
    return lookup(solver).family


def solve(solver: str | Solver, case, progress: Callable[[int, int], None] | None = None,
          fields: bool = False, options=None, every: int = 0) -> RunResult:
    """Run ``case`` with ``solver`` (a name, or its entry); ``fields``: keep the synthesized 3-D
    field of the last step in ``result.mesh`` (else None); ``every``: also the field every that
    many steps in ``result.frames`` (where the solver supports ``frames``); ``options``: SMFEM's
    :class:`smfem.options.SolverOptions` (or a dict of its fields); for the reference FEM a
    dict of keyword arguments of its ``solve`` (``grading``; the explicit one also
    ``step_divisor``)."""
    entry = _entry(solver)
    case = with_fixed(entry, case)
    if entry.options_fixed:
        options = _with_fixed_options(entry, options or {})
    if FORCES not in entry.supports and (case.forces or case.variation):
        from cases import UnsupportedCase

        raise UnsupportedCase(f"{case.name}: body forces and a material varying along x3 are solved by smfem and the "
                              f"reference FEM so far, not by {entry.name}")
    result = entry.run(case, progress=progress, fields=fields, every=every, options=options)
    return result if fields or result.mesh is None else replace(result, mesh=None)


def _with_fixed_options(entry: Solver, options: dict) -> dict:
    """``options`` with those the entry fixes; another value for one of them is refused in one line."""
    for key, value in entry.options_fixed:
        if options.get(key, value) != value:
            raise ParameterError(f"{entry.name} runs with {key}={value}, not {key}={options[key]}")
    return options | entry.fixed_options


# -- how each solver runs: its module imported only then ---------------------------------------
def _smfem(case, progress, fields, every, options) -> RunResult:
    from smfem.solver import solve as smfem

    options = _smfem_make_options(options) if isinstance(options, dict) else options
    return smfem(case, options, progress=progress, with_fields=fields, every=every)


def _reference(case, progress, fields, every, options) -> RunResult:
    from reference_fem import solve as reference

    return reference(case, progress=progress, every=every, fields=fields, **(options or {}))


def _explicit(case, progress, fields, every, options) -> RunResult:
    from reference_fem.explicit import solve as explicit

    return explicit(case, progress=progress, every=every, fields=fields, **(options or {}))


def _modal(case, progress, fields, every, options) -> RunResult:
    from reference_fem.modal import solve as modal

    return modal(case, progress=progress)


def _calculix(case, progress, fields, every, options) -> RunResult:
    from reference_fem.calculix import solve as calculix

    return calculix(case, progress=progress, **(options or {}))


def _ccx_installed() -> bool:
    """``ccx`` is on PATH or at ``SMFEM_CCX`` (CalculiX's own lookup, imported when asked)."""
    from reference_fem.calculix import CalculixMissing, find_ccx

    try:
        return bool(find_ccx())
    except CalculixMissing:
        return False


def _smfem_options() -> dict:
    from smfem.options import SPECS

    return SPECS


def _smfem_make_options(options: dict):
    from smfem.options import SolverOptions

    return SolverOptions(**options)


def _smfem_checks() -> dict:
    from smfem import checks

    return {name: getattr(checks, name) for name in ("static_probes", "explicit_limit", "free_vibration",
                                                    "stiffness_condition")}


def _reference_checks() -> dict:
    from reference_fem import checks

    return {"static_probes": checks.static_probes}


#: the reference FEM's own options, checked as case parameters are (here, not in its package:
#: ``smfem run`` reads every solver's option names and must not load the reference to do so)
_ELEMENT_OPTIONS = {
    # beta of the geometric grading toward a cut-out's corner lines (1: uniform); far past 8 the
    # smallest element is a round-off of the span
    "grading": Spec(float, 1.0, 8.0, help="mesh grading toward the re-entrant corner lines (1: uniform)"),
    "bbar": Spec(bool, help="B-bar: the volumetric strain projected per element"),
}
_REFERENCE_OPTIONS = {
    **_ELEMENT_OPTIONS,
    # reference_fem.linalg.LINEAR_SOLVERS (named here: this module must not import the reference)
    "linear_solver": Spec(str, choices=("auto", "superlu", "pcg"),
                          help="Newton tangents: CG on the elastic factors (pcg), factorized (superlu), or auto"),
}
#: CalculiX's own options (reference_fem.calculix.procedures' names and bounds, written here as the
#: reference's are)
_CALCULIX_OPTIONS = {
    "procedure": Spec(str, choices=("implicit", "explicit", "modal"),
                      help="ccx's procedure: *DYNAMIC (implicit, the default), *DYNAMIC, EXPLICIT (linear elements, "
                           "lumped mass, ccx's Courant increment) or *FREQUENCY then *MODAL DYNAMIC (modal)"),
    "modes": Spec(int, 1, 20000, help="the modal procedure's mode count (default 100; fewer than the mesh's free dofs)"),
}
_EXPLICIT_OPTIONS = {
    **_ELEMENT_OPTIONS,
    "step_divisor": Spec(int, 1, 1000, help="divides the explicit step (a time ladder)"),
}


def checked(options: dict, specs: dict) -> dict:
    """``options`` with each value checked and converted by its spec (:class:`cases.ParameterError`)."""
    for key in options:
        if key not in specs:
            raise ParameterError(f"unknown option {key!r}: allowed are {', '.join(sorted(specs))}")
    return {key: specs[key].check(key, value) for key, value in options.items()}


_ON_A_MESH = dict(run=_reference, family=REFERENCE, estimated=True, options=partial(dict, _REFERENCE_OPTIONS),
                  make_options=partial(checked, specs=_REFERENCE_OPTIONS), checks=_reference_checks)  # by dim
register(Solver(SMFEM, _smfem, packages=("smfem",), label="SMFEM", color="C0", marker="o", harmonics=True,
                estimated=True, options=_smfem_options, make_options=_smfem_make_options, checks=_smfem_checks))
register(Solver(SMFEM_QUAD9, _smfem, fixes=(("element", "quad9"),), family=SMFEM, packages=("smfem",),
                label="SMFEM quad9", color="C3", marker="*", prose="SMFEM with the quadratic element", harmonics=True,
                estimated=True, command_line=False, options=_smfem_options, make_options=_smfem_make_options,
                checks=_smfem_checks))
register(Solver(REFERENCE, **_ON_A_MESH, label="reference FEM", color="C1", marker="s", series=False))
register(Solver(REF2D, **_ON_A_MESH, dim=2, label="reference FEM 2D", color="C1", marker="s",
                prose="the 2D reference", command_line=False))
register(Solver(REF3D, **_ON_A_MESH, dim=3, label="reference FEM 3D", color="C2", marker="^",
                prose="the 3D reference", command_line=False, dear=True, variant="implicit"))
# its explicit engine (central differences, lumped mass, its own Courant step), a series of its own
# in the 3D row; what it cannot take (a wall with plasticity or friction) it refuses itself
_CENTRAL = dict(run=_explicit, family=EXPLICIT, supports=EVERYTHING - {FORCES}, courant=True,
                options=partial(dict, _EXPLICIT_OPTIONS), make_options=partial(checked, specs=_EXPLICIT_OPTIONS))
register(Solver(REF3D_EXPLICIT, **_CENTRAL, dim=3, headline=REF3D, variant="explicit",
                label="reference FEM 3D, explicit", color="C2", marker="<", prose="the 3D reference's explicit engine",
                command_line=False, dear=True))
register(Solver(MODAL, _modal, supports=frozenset(), label="reference FEM, harmonic model", color="C5", marker="v",
                harmonics=True, command_line=False, series=False))
_CCX = dict(run=_calculix, family=CALCULIX, color="C4", dear=True, options=partial(dict, _CALCULIX_OPTIONS),
            make_options=partial(checked, specs=_CALCULIX_OPTIONS), installed=_ccx_installed)
register(Solver(CALCULIX, **_CCX, supports=frozenset((PLASTICITY, FORCES)), label="CalculiX", marker="D",
                prose="CalculiX", variant="implicit"))
# its other procedures, series of their own; what each cannot take it refuses itself (modal: plasticity)
register(Solver(CALCULIX_EXPLICIT, **_CCX, options_fixed=(("procedure", "explicit"),),
                supports=frozenset((PLASTICITY, FORCES)), label="CalculiX explicit", marker=">",
                prose="CalculiX's explicit procedure", command_line=False, courant=True))
register(Solver(CALCULIX_MODAL, **_CCX, options_fixed=(("procedure", "modal"),), supports=frozenset((FORCES,)),
                label="CalculiX modal", marker="d", prose="CalculiX's modal procedure", command_line=False))
register(Solver(EXPLICIT, **_CENTRAL, label="reference FEM, explicit", color="C6", marker="P", series=False))
