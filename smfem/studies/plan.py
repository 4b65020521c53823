"""What a study runs: per case, series of runs (one per solver) over space and time levels,
the run that the same-dt (spatial) comparison measures against, and how the truth is made.

A level is a dict of ``--set`` overrides (``refine``, ``harmonics``, ``dt``) and of the solver's
own options (CalculiX's ``modes``: :func:`smfem.runs.registry.split_level`); every run of a
case also gets the case study's ``base`` overrides (a shorter window for a tiny study, say).
A series spans the mesh (and harmonics) and the time step together, so that its
work-precision front is that of the total error (:mod:`reports.analysis`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from cases import ParameterError, get_case
from smfem.runs.registry import (CALCULIX, CALCULIX_EXPLICIT, CALCULIX_MODAL, EXPLICIT, MODAL, REF2D, REF3D,
                                 REF3D_EXPLICIT, REFERENCE, SMFEM, SMFEM_QUAD9, lookup, solvers)

#: the ``--set`` keys that make a level
RESOLUTION_KEYS = ("refine", "coarsen", "harmonics", "dt")
#: time steps of the quick study's 3-D series, as divisors of the case's: twice, once and half
#: the case's (3-D errors are mostly spatial, and a 3-D step is dear)
THREE_D = (0.5, 1, 2)
#: the solvers whose error estimates the quick and full reports measure against the truth (a 3-D
#: run's companions are 3-D runs too, dear for the quick report's 10 minutes)
ESTIMATED_SERIES = (SMFEM, REF2D)
#: how a truth is made (:mod:`smfem.studies.truth`)
MODAL_TRUTH, TIME_TRUTH, EXPLICIT_TRUTH = "modal", "time-step halving", "explicit"
TRUTH_METHODS = (MODAL_TRUTH, TIME_TRUTH, EXPLICIT_TRUTH)


@dataclass(frozen=True)
class Until:
    """Where a series carried along its ladder stops (:mod:`smfem.studies.ladder`): at its first run
    whose total error (the headline measure against the stored truth) is at most ``target``,
    or before a level whose CPU time, predicted from the last run's, would pass ``budget_s``."""

    target: float = 0.01
    budget_s: float = 900.0

    def __post_init__(self):
        if not (0 < self.target < 1 and self.budget_s > 0):
            raise ValueError("a series is carried to a target error in (0, 1) within a positive CPU budget")

    def describe(self) -> str:
        return f"until {100 * self.target:g} % or {self.budget_s:g} CPU s a run"


@dataclass(frozen=True)
class Series:
    """Runs of one solver over levels, with the solver's own ``options`` (sorted ``(key,
    value)`` pairs, as a :class:`~smfem.studies.jobs.Job`'s: e.g. the reference's B-bar element).

    With ``until``, the levels are a ladder, run one after another in the order of their
    predicted work while the last run is above the target (:class:`Until`); without, every
    level runs (at once)."""

    solver: str
    levels: tuple[dict, ...]
    options: tuple = ()
    until: Until | None = None

    def __post_init__(self):
        if not lookup(self.solver).series:
            raise ValueError(f"solver must be one of {series_solvers()}, not {self.solver!r}")


def series_solvers() -> tuple[str, ...]:
    """The solvers a study may have series of, in the table's order (the modal and explicit
    solutions make truths only; CalculiX, optional, a series per procedure)."""
    return tuple(s.name for s in solvers() if s.series)


@dataclass(frozen=True)
class TruthPlan:
    """How the truth of a case is made, converged in space, harmonics and time.

    ``modal`` (linear scenes homogeneous along x3): the harmonic model exactly in time, sampled
    every ``dt / output_divisor``, over the ``refine`` ladder at the last of ``harmonics``
    and over the ``harmonics`` ladder at the last ``refine`` (ratio 2 each; an axisymmetric
    case has no harmonics ladder).

    ``time-step halving`` (plastic, contact, cut-outs): ``solver`` on ``refine[0]`` at
    ``dt / d`` for each of ``dt_divisors``, Richardson in dt where the observed order is near
    2; the meshes ``refine`` at ``dt / space_dt_divisor`` (one of ``dt_divisors``; 1: the
    case's dt) correct it to the finest and bound what is left. A scene whose meshes differ
    at the case's dt by their time errors (contact events: ring_in_ring) sets a finer one.

    ``explicit`` (plastic, contact, cut-outs): the explicit reference
    (:mod:`reference_fem.explicit`, central differences at a fixed fraction of the critical
    step, so the step halves with the mesh) over the ``refine`` ladder (each level twice the
    last), sampled every ``dt / output_divisor``, at ``dim`` (2 or 3) with the solver
    ``options`` (B-bar, mesh grading). Richardson's extrapolation of the three finest levels
    at their observed order is the truth where it is checked by the ``check`` pair (an
    interleaved ladder, e.g. r3 and r6 beside r2, r4, r8), extrapolated at the same order;
    else the finest level with its grid convergence index.
    """

    method: str
    refine: tuple[int, ...]
    harmonics: tuple[int, ...] = ()
    dt_divisors: tuple[int, ...] = (1, 2, 4)
    solver: str = REF2D
    output_divisor: int = 16
    dim: int = 2
    options: tuple = ()
    check: tuple[int, ...] = ()
    space_dt_divisor: int = 1

    def __post_init__(self):
        if self.method not in TRUTH_METHODS:
            raise ValueError(f"truth method must be one of {TRUTH_METHODS}")
        if self.method == TIME_TRUTH and (len(self.refine) < 2 or len(self.dt_divisors) < 3):
            raise ValueError("a time-step-halving truth needs two meshes or more and at least three dt levels")
        if self.method == TIME_TRUTH and self.space_dt_divisor not in self.dt_divisors:
            raise ValueError("a time-step-halving truth's meshes run at one of its dt levels")
        if self.method == EXPLICIT_TRUTH:
            if len(self.refine) < 2 or any(b != 2 * a for a, b in zip(self.refine, self.refine[1:])):
                raise ValueError("an explicit truth needs two meshes or more, each twice as fine as the last")
            if self.check and (len(self.check) != 2 or self.check[1] != 2 * self.check[0]):
                raise ValueError("an explicit truth's check is a pair of meshes, the second twice as fine")

    def describe(self) -> dict:
        """What identifies the plan (its part of a stored truth's key)."""
        out = {"method": self.method, "refine": list(self.refine), "output_divisor": self.output_divisor}
        if self.method == MODAL_TRUTH:
            out["harmonics"] = list(self.harmonics)
        if self.method == TIME_TRUTH:
            out |= {"solver": self.solver, "dt_divisors": list(self.dt_divisors)}
            if self.space_dt_divisor != 1:  # (absent at 1: the stored truths' keys from before it stay valid)
                out["space_dt_divisor"] = self.space_dt_divisor
        if self.method == EXPLICIT_TRUTH:
            out |= {"solver": self.solver, "dim": self.dim, "options": dict(self.options), "check": list(self.check)}
        return out


@dataclass(frozen=True)
class CaseStudy:
    """The runs that measure one case: series per solver, the finest reference-FEM run at the
    case's dt (the same-dt comparison, as the paper made it) and the truth.

    The SMFEM run at the case's own settings (no level overrides) also writes ``fields.vtu``
    and plastic zones, for the 3-D view. Each solver of ``estimated`` has its error estimate
    measured against the truth at three settings (:mod:`smfem.studies.effectivity`).
    """

    case: str
    series: tuple[Series, ...]
    #: the same-dt reference run, ``(solver, level)`` or ``(solver, level, options)`` (a series'
    #: run, when its options are that series'); None where the reference FEM is past the study
    #: (3D only)
    reference: tuple | None
    truth: TruthPlan | None = None
    base: dict = field(default_factory=dict)
    estimated: tuple[str, ...] = ()
    #: ``(solver, why)``: a solver that takes the scene but has no series here, and why in one
    #: line (its first run past the budget or the machine), said in the report beside the rows
    left_out: tuple[tuple[str, str], ...] = ()


#: the meshes of an explicit truth: the ladder r2, r4, r8 and the interleaved pair r3, r6 that
#: checks its extrapolation (:class:`TruthPlan`)
EXPLICIT_LADDER = dict(refine=(2, 4, 8), check=(3, 6))


def explicit_truth(ladder: dict = EXPLICIT_LADDER, **options) -> TruthPlan:
    """An explicit truth over ``ladder`` (:data:`EXPLICIT_LADDER`) with the solver ``options``."""
    return TruthPlan(EXPLICIT_TRUTH, solver=EXPLICIT, options=tuple(sorted(options.items())), **ladder)


#: the notched moving load's explicit ladder: r1, r2, r4 (the finest with its grid convergence
#: index). Its r8 would be 3 CPU hours a path (t_end 6e-4 s, twice the notched strip's), and the
#: ladder converges at order 1.04-1.07 from r1 on: r4 is within a few tenths of a per cent
MOVING_NOTCHED_LADDER = dict(refine=(1, 2, 4))


#: the flywheel's truth: the harmonic model on the section's 9-node elements and on them split
#: 2 x 2, exact in time (the 9-node reference converges fast here: the two meshes differ by about
#: 1e-4 at the rim); split 4 x 4 it would be hours (1500 CPU s at 2 x 2)
FLYWHEEL_TRUTH = TruthPlan(MODAL_TRUTH, refine=(1, 2), harmonics=(6, 12, 24))
#: ring_in_ring's truth: the 2D reference (plane strain) at r1 down to dt / 64 (each closure of
#: the clearance makes the time error first order), corrected to r4 at dt / 32, where the
#: meshes differ by their space errors (at the case's dt by their time errors as much: r2 to r3
#: moved the displacements 0.9-1.6 % at dt; at dt / 8 the friction's first-order time error,
#: 0.3-0.6 % and growing with the mesh, still passed for mesh error and left the truth 0.2-0.45 %
#: from its explicit path; from dt / 32 to dt / 64 it moves 0.03-0.06 %)
RING_TRUTH = TruthPlan(TIME_TRUTH, refine=(1, 2, 4), dt_divisors=(1, 2, 4, 8, 16, 32, 64), solver=REF2D,
                       space_dt_divisor=32)
#: the flywheel's 3D reference runs: its mirror half (the patch is symmetric about theta = 0),
#: 16, 24 and 32 elements round the whole (64 would be 1.3 million unknowns in the whole; 24 is
#: 1.7 % off the truth, 32 peaks at 14.3 GB: the scheduler starts nothing beside it that would
#: pass the machine's memory, smfem/studies/peak_memory.py)
FLYWHEEL_3D = tuple({"mirror": True, "theta_elements": n} for n in (16, 24, 32))
#: where the flywheel's 3D series stops: at 1 %, within 2400 CPU s a run, not :data:`FULL_UNTIL`'s
#: 900: 24 round (676 CPU s, 1.72 %) predicts 32 round at 901 s by its unknowns, and the 3D
#: reference's cell at 1 % is what the flywheel's row asks (16 to 24 round: 7.3 to 1.72 %, so 32
#: round about 0.6 %)
FLYWHEEL_3D_UNTIL = Until(target=0.01, budget_s=2400.0)
#: why the full plan runs the flywheel's explicit 3D engine nowhere (benchmarks/README.md)
FLYWHEEL_EXPLICIT = ("its Courant step on the mirror half at 16 round is 3.7e-8 s (the fillets' 2.5 mm elements): "
                     "134,000 steps of 165,424 unknowns, about 5500 CPU s for its first run, past the budget")
#: why the full plan runs the colliding rods in 3D with neither engine
ROD_COLLISION_3D = ("neither 3D engine: the two rods' section swept 64 round is 48,000 hexahedra at refine 1, whose "
                    "basis alone passes 8 GB")


def _s(solver, *levels, until: Until | None = None, **options):
    return Series(solver, tuple(levels), tuple(sorted(options.items())), until)


#: CalculiX's modal levels: meshes x modes (its truncation measured like any other parameter);
#: three meshes: the layered cylinder's r2 at 800 modes is 1.09 % (1922 CPU s; r2 at 400 1.23 %)
CCX_MODAL = tuple({"refine": r, "modes": m} for r in (1, 2, 3) for m in (50, 100, 200, 400, 800))
#: CalculiX's explicit levels: meshes (its increment is ccx's own, from the Courant limit); r3
#: between r2 and r4, as its CPU grows as the mesh cubed (thick cylinder: r1 3.19 %, 61 CPU s; r2
#: 1.56 %, 420 s; r3 1.04 %, 1600 s; r4 about 0.8 %, predicted 3400-3800 s)
CCX_EXPLICIT = tuple({"refine": r} for r in (1, 2, 3, 4))
#: where CalculiX's explicit and modal series stop: at 1 % as every series, but within 8000 CPU s a
#: run, not :data:`FULL_UNTIL`'s 900: below 1 % explicit needs r3 or r4 on the thick, layered and
#: notched cylinders and the pulse (B_ut and the patch edges converge at first order in the mesh;
#: r4 on the layered cylinder and the pulse is predicted at 7100-7200 s from r3), modal 800 modes
#: on the finer mesh where 400 stop at 1.2-2 % (predicted 1500-2100 s), and a ccx user after 1 %
#: would run them (docs/verification.md, CalculiX against the exact answer)
CCX_UNTIL = Until(target=0.01, budget_s=8000.0)


#: the explicit 3D reference's levels: meshes (its step is its own Courant limit, half the critical
#: step, so it shrinks with the mesh); r3, as the implicit 3D ladders, is the finest a run of the
#: full report takes beside another on this machine's memory
EXPLICIT_3D = tuple({"refine": r} for r in (1, 2, 3))


def explicit_3d(**options) -> Series:
    """The 3D reference's explicit engine over :data:`EXPLICIT_3D`, with its solver ``options``
    (B-bar): a series of its own, in the headline's 3D row, whose cells are the cheaper engine's."""
    return _s(REF3D_EXPLICIT, *EXPLICIT_3D, **options)


#: the quick report's CalculiX series: its cheapest procedure, modal, at two mode counts
#: (benchmarks/README.md), where the scene's mesh takes them (the dome's: 50 modes, two meshes)
QUICK_MODAL = ({"modes": 50}, {"modes": 100})


def calculix(explicit: bool = True, modal: bool = True) -> tuple[Series, ...]:
    """CalculiX's procedures on a scene of the full plan: implicit at the case's settings (ccx's
    dearest: two factorizations an increment), explicit over the meshes (ccx's own Courant
    increment, :data:`CCX_EXPLICIT`) and modal over :data:`CCX_MODAL`; a procedure the scene cannot take (``explicit``
    or ``modal`` False: plasticity, contact, an initial velocity) is one run, refused in the
    solver's one line, which the report keeps."""
    return (_s(CALCULIX, {}), _s(CALCULIX_EXPLICIT, *(CCX_EXPLICIT if explicit else ({},)),
                                 until=CCX_UNTIL if explicit else None),
            _s(CALCULIX_MODAL, *(CCX_MODAL if modal else ({},)), until=CCX_UNTIL if modal else None))


def installed(*series: Series) -> tuple[Series, ...]:
    """``series`` whose solvers' programs are on this machine (the quick report's light CalculiX
    series: none without ccx)."""
    return tuple(s for s in series if lookup(s.solver).installed())


def grid(case: str, spaces, divisors) -> tuple[dict, ...]:
    """Every space level (dicts of ``refine``/``harmonics``) at every ``dt`` = the case's dt
    over each of ``divisors`` (a divisor below 1: a longer step than the case's)."""
    dt = get_case(case).dt
    return tuple({**s, "dt": dt / d} if d != 1 else dict(s) for s in spaces for d in divisors)


def _r(*values):
    return tuple({"refine": v} for v in values)


def quick() -> tuple[CaseStudy, ...]:
    """The default report: every solver over meshes up to a few times the paper's and at
    least three time steps (the case's, half and a quarter of it, more where cheap; twice it
    where a quarter is dear and adds little), so that the whole study runs within 10 minutes on
    two cores (the scenes' truths are stored: ``truths/``). The report: 9 min 10 s on two cores
    of the slower machine (AMD EPYC, AVX2 only) with the install in a fresh clone (2026-11-27,
    eleven scenes, 380 runs, the error estimates' companions included)."""
    return _estimated(*_quick_studies(), unestimated=("flywheel", "ring_in_ring"), smfem_only=("notched_strip",))


def _quick_studies() -> tuple[CaseStudy, ...]:
    """The quick study's scenes (:func:`quick`)."""
    return (
        CaseStudy("dome", (
            _s(SMFEM, *grid("dome", _r(1, 2, 4), (1, 2, 4, 8)), *grid("dome", _r(8), (1, 2, 4))),
            _s(SMFEM_QUAD9, *grid("dome", _r(1), (1, 2, 4)), *grid("dome", _r(2), (1, 2, 4, 8))),
            _s(REF2D, *grid("dome", _r(1, 2, 4), (1, 2, 4))),
            _s(REF3D, *grid("dome", _r(1), THREE_D)),
            # CalculiX: two levels of its cheapest procedure here, modal (benchmarks/README.md)
            *installed(_s(CALCULIX_MODAL, {"refine": 1, "modes": 50}, {"refine": 2, "modes": 50})),
        ), reference=(REF2D, {"refine": 8}), truth=TruthPlan(MODAL_TRUTH, refine=(1, 2, 4))),
        CaseStudy("thick_cylinder", (
            _s(SMFEM, *grid("thick_cylinder", ({"harmonics": 20}, {"refine": 2, "harmonics": 40},
                                               {"refine": 4, "harmonics": 80}), (1, 2, 4, 8, 16, 32)),
               *grid("thick_cylinder", ({"refine": 4, "harmonics": 80},), (64,))),
            # the quadratic element: time-limited from 1 % on (its space error at r1 H80 is 0.7 %)
            _s(SMFEM_QUAD9, *grid("thick_cylinder", ({"harmonics": 20},), (1, 4, 16)),
               *grid("thick_cylinder", ({"harmonics": 40},), (4, 16, 32)),
               *grid("thick_cylinder", ({"harmonics": 80},), (16, 32)),
               *grid("thick_cylinder", ({"refine": 2, "harmonics": 80},), (32, 64)),
               # ... and with the order-4 Gauss scheme in time (benchmarks/time_schemes.py: the one
               # time treatment that moves this front; not the dome's, limited by space from dt/2 on)
               *grid("thick_cylinder", ({"harmonics": 40, "time_scheme": "gauss"},), (1, 4)),
               *grid("thick_cylinder", ({"harmonics": 80, "time_scheme": "gauss"},), (1, 2, 4)),
               *grid("thick_cylinder", ({"refine": 2, "harmonics": 80, "time_scheme": "gauss"},), (4,))),
            _s(REF2D, *grid("thick_cylinder", _r(1), (1, 2, 4, 8, 16)), *grid("thick_cylinder", _r(2), (1, 2, 4, 8))),
            # dt / 4 (about 7 CPU s) is where the 3D mesh reaches 5 %
            _s(REF3D, *grid("thick_cylinder", _r(1), (*THREE_D, 4))),
            # CalculiX: its cheapest procedure here, modal (its other procedures and finer meshes
            # are the full report's)
            *installed(_s(CALCULIX_MODAL, *QUICK_MODAL)),
        ), reference=(REF2D, {"refine": 3}),
            truth=TruthPlan(MODAL_TRUTH, refine=(2, 4, 8), harmonics=(160, 320, 640))),
        CaseStudy("notched_cylinder", (
            _s(SMFEM, *grid("notched_cylinder", ({"harmonics": 20}, {"harmonics": 40}, {"refine": 2, "harmonics": 40}),
                            (1, 2, 4)), *grid("notched_cylinder", ({"refine": 2, "harmonics": 80},), (1, 2))),
            # the quadratic element: the only SMFEM series below 5 % here (r2 H80: 4.6 %; at dt / 2
            # 4.2 % for 18 CPU s more: the full report's)
            _s(SMFEM_QUAD9, *grid("notched_cylinder", ({"harmonics": 40},), (0.5, 1)),
               *grid("notched_cylinder", ({"harmonics": 80},), (1, 2)), {"refine": 2, "harmonics": 80}),
            # the 2D reference stops at r2 here: r3 (100 CPU s, 4.3 -> 3.6 % total error) put the
            # report over its 10 minutes once the stored truth had made it unnecessary as a truth level
            _s(REF2D, *grid("notched_cylinder", _r(1), (1, 2, 4)), {"refine": 2}),
            # 3D at dt (2 dt, 10 CPU s more, and dt / 2, 38 s: the full report's; the 3D error here
            # is its mesh's); no CalculiX (160 CPU s for 7 % against the truth, neither target)
            _s(REF3D, *grid("notched_cylinder", _r(1), (1,))),
        ), reference=(REF2D, {"refine": 2}), truth=TruthPlan(TIME_TRUTH, refine=(1, 2, 3))),
        CaseStudy("notched_strip", (
            # harmonics-limited: half the step changes nothing (H120: 0.89 -> 0.96 %), twice it little
            _s(SMFEM, *grid("notched_strip", ({"harmonics": 40}, {"harmonics": 80}, {"harmonics": 100},
                                              {"harmonics": 120}, {"harmonics": 160}), (0.5, 1)),
               *grid("notched_strip", ({"harmonics": 120},), (2,))),
            # the quadratic element gains nothing on a harmonics-limited scene: its front points
            _s(SMFEM_QUAD9, *grid("notched_strip", ({"harmonics": 120, "coarsen": 2},), (0.5, 1, 2)),
               *grid("notched_strip", ({"harmonics": 120},), (1,))),
            # 2 dt rather than dt / 4 (30 CPU s for 0.96 -> 0.93 %): the report's 10 minutes. Its
            # tangents factorized: ideal plasticity over the whole ligament leaves CG 33 iterations a
            # Newton step on the elastic factors (r1 20-21 against 23-34 CPU s in three runs, r2 120
            # against 216 s: benchmarks/reference_linear_solver.py); no r2 (0.28 %: the full report's)
            _s(REF2D, *grid("notched_strip", _r(1), (0.5, 1, 2)), linear_solver="superlu"),
            # 3D at 2 dt: its mesh's limit (2.28 %; dt 2.34 % for 38 CPU s more, dt / 2 2.1 %); no
            # CalculiX (260 CPU s for 1.3 %, a third of the study's CPU, put the report over its 10
            # minutes once the error estimates came in): the full report has both
            _s(REF3D, *grid("notched_strip", _r(1), (0.5,))),
        ), reference=(REF2D, {"refine": 1}, (("linear_solver", "superlu"),)), truth=TruthPlan(TIME_TRUTH, refine=(1, 2))),
        CaseStudy("rod_impact", (
            _s(SMFEM, *grid("rod_impact", _r(1, 2), (1, 2, 4)), *grid("rod_impact", _r(4), (1, 2))),
            # the quadratic element's contact layer (time-limited against the truth, as every run here)
            _s(SMFEM_QUAD9, *grid("rod_impact", _r(1), (1, 2, 4))),
            # time-limited: r2 and r4 at a step are r1's error to a few hundredths of a per cent
            _s(REF2D, *grid("rod_impact", _r(1), (1, 2, 4)), {"refine": 2}),
            # elastic: 8 and 4 dt are points as good as dt / 2 for the report's 10 minutes (2 dt
            # reaches 1 %; dt, 0.27 %, 39 CPU s: the full report's)
            _s(REF3D, *grid("rod_impact", _r(1), (0.125, 0.25, 0.5))),
            _s(CALCULIX, {}),
        ), reference=(REF2D, {"refine": 2}), truth=TruthPlan(TIME_TRUTH, refine=(2, 4))),
        # the sections issue's scenes: light series (the full report carries the rest)
        CaseStudy("layered_cylinder", (
            # time-limited as the thick cylinder: SMFEM reaches 5 % from dt / 8 (its runs are 0.1 s)
            _s(SMFEM, *grid("layered_cylinder", ({"harmonics": 20}, {"refine": 2, "harmonics": 40}), (1, 2, 4, 8, 16))),
            _s(REF2D, *grid("layered_cylinder", _r(1, 2), (1, 2, 4))),
            # no CalculiX (44 CPU s, the report's 10 minutes once the contact scenes came in): the full report's
        ), reference=(REF2D, {"refine": 2}),
            truth=TruthPlan(MODAL_TRUTH, refine=(1, 2, 4), harmonics=(20, 40, 80))),
        # its truth is stored (smfem/truths/flywheel: 3000 CPU s); no same-dt reference: its reference
        # FEM and CalculiX are 3D only (the load is not axisymmetric), 1.3 million unknowns
        CaseStudy("flywheel", (
            _s(SMFEM, *grid("flywheel", ({},), (0.25, 0.5, 1))),
        ), reference=None,
            truth=FLYWHEEL_TRUTH),
        # the loads issue's scenes: light series, CalculiX's modal procedure at 50 and 100 modes
        # (its implicit one, past the report's 10 minutes, is the full report's); the notched
        # moving load (its 2D reference: 20 CPU s a run at refine 1) is the full report's
        CaseStudy("layered_cylinder_pulse", (
            # B_ut, the hoop displacement at a patch's edge, needs many harmonics and short steps:
            # r4 H160 at dt / 32 is 0.63 % from the truth (2 CPU s), r2 H40 stops at 2.2 %
            _s(SMFEM, *grid("layered_cylinder_pulse", ({"harmonics": 20}, {"refine": 2, "harmonics": 40}),
                            (1, 2, 4, 8, 16)),
               *grid("layered_cylinder_pulse", ({"refine": 4, "harmonics": 160},), (16, 32))),
            _s(REF2D, *grid("layered_cylinder_pulse", _r(1), (1, 2, 4)), {"refine": 2}),
            *installed(_s(CALCULIX_MODAL, *QUICK_MODAL)),
        ), reference=(REF2D, {"refine": 2}),
            truth=TruthPlan(MODAL_TRUTH, refine=(1, 2, 4), harmonics=(20, 40, 80))),
        CaseStudy("moving_load", (
            _s(SMFEM, *grid("moving_load", ({"harmonics": 20}, {"harmonics": 60}, {"harmonics": 120}), (0.5, 1, 2, 4))),
            _s(REF2D, *grid("moving_load", _r(1), (0.5, 1, 2)), {"refine": 2}),
            *installed(_s(CALCULIX_MODAL, *QUICK_MODAL)),
        ), reference=(REF2D, {"refine": 2}),
            truth=TruthPlan(MODAL_TRUTH, refine=(1, 2, 4), harmonics=(60, 120, 240))),
        # the interaction issue's scenes: light series (the full report carries the rest)
        CaseStudy("rod_collision", (
            _s(SMFEM, *grid("rod_collision", _r(1, 2), (1, 2, 4))),
            _s(SMFEM_QUAD9, *grid("rod_collision", _r(1), (1, 2, 4))),
            _s(REF2D, *grid("rod_collision", _r(1), (1, 2, 4)), {"refine": 2}),
            _s(CALCULIX, {}),  # refused: the report says why (its contact pairs stop, measured)
        ), reference=(REF2D, {"refine": 2}),
            truth=explicit_truth()),
        CaseStudy("ring_in_ring", (
            _s(SMFEM, *grid("ring_in_ring", ({"harmonics": 20},), (1, 2, 4, 8))),
            _s(REF2D, *grid("ring_in_ring", _r(1), (1, 2, 4))),
            # no 3D (plane strain in 3D, one element along the axis: the 2D reference's histories
            # to 1e-10 at 15 times its CPU, 92 CPU s: the full report's)
            _s(CALCULIX, {}),
        ), reference=(REF2D, {"refine": 1}),
            truth=RING_TRUTH),
    )


#: where the full report's series stop: 1 % total error, or a run predicted past 900 CPU s
FULL_UNTIL = Until(target=0.01, budget_s=900.0)


def carried(studies: tuple[CaseStudy, ...], until: Until = FULL_UNTIL) -> tuple[CaseStudy, ...]:
    """``studies`` with every series of more than one level carried ``until`` (:class:`Until`),
    or its own where it has one (CalculiX's explicit and modal: :data:`CCX_UNTIL`; the flywheel's
    3D reference: :data:`FLYWHEEL_3D_UNTIL`)."""
    return _each_series(studies, lambda case, x: replace(x, until=x.until or until) if len(x.levels) > 1 else x)


def full() -> tuple[CaseStudy, ...]:
    """The larger study: finer meshes, more time steps, both SMFEM elements, 3-D at two meshes
    or more, every series carried along its ladder to 1 % or its CPU budget (:data:`FULL_UNTIL`),
    with every level of the quick study's series (:func:`with_quick_levels`) and each time-stepping
    ladder's space levels also at twice their longest step (:func:`with_longer_step`)."""
    return carried(with_quick_levels(_each_series(_full_studies(), with_longer_step), _quick_studies()))


def _each_series(studies: tuple[CaseStudy, ...], change) -> tuple[CaseStudy, ...]:
    """``studies`` with each series replaced by ``change(case, series)``."""
    return tuple(replace(s, series=tuple(change(s.case, x) for x in s.series)) for s in studies)


def _filled(level: dict, dt: float) -> dict:
    """``level`` with the defaults it leaves out (``refine`` 1, the case's step ``dt``): two
    levels that make the same run compare equal."""
    return {"refine": 1, "dt": dt, **level}


def with_quick_levels(studies: tuple[CaseStudy, ...], quick_studies: tuple[CaseStudy, ...]) -> tuple[CaseStudy, ...]:
    """``studies`` with each level of ``quick_studies``' series that the series of the same
    solver and options lacks: a ladder runs its levels cheapest first, so the full report never
    misses a cheaper run to a target that the quick report makes (its 3D dome at twice the
    step: 3.4 % in 2.9 CPU s, where the full ladder's cheapest to 5 % was r2 at 148 s)."""
    quick_of = {q.case: q.series for q in quick_studies}

    def added(case: str, series: Series) -> Series:
        if len(series.levels) < 2:
            return series
        dt = get_case(case).dt
        have = [_filled(level, dt) for level in series.levels]
        extra = [level for q in quick_of.get(case, ()) if (q.solver, q.options) == (series.solver, series.options)
                 for level in q.levels if _filled(level, dt) not in have]
        return replace(series, levels=(*series.levels, *extra))

    return _each_series(studies, added)


def with_longer_step(case: str, series: Series) -> Series:
    """``series`` with each space level also at twice the longest step the series gives it, where
    the series spans the time step (a level sets ``dt``) and its solver steps at the ``dt`` it is
    given (not at its own Courant limit): a competent user tries the longer step first, and a
    ladder runs it first, being cheaper (the moving load's 2D reference reaches 1 % at twice the
    case's step in 0.39 CPU s, 1.05 s at the case's)."""
    if len(series.levels) < 2 or lookup(series.solver).courant or not any("dt" in level for level in series.levels):
        return series
    dt = get_case(case).dt
    longest: dict[tuple, float] = {}
    for level in series.levels:
        filled = _filled(level, dt)
        space = tuple(sorted((k, v) for k, v in filled.items() if k != "dt"))
        longest[space] = max(longest.get(space, 0.0), filled["dt"])
    return replace(series, levels=(*series.levels, *({**dict(space), "dt": 2 * step} for space, step in longest.items())))


def _full_studies() -> tuple[CaseStudy, ...]:
    """The full study's scenes, their ladders whole (:func:`full`)."""
    return _estimated(
        CaseStudy("dome", (
            _s(SMFEM, *grid("dome", _r(1, 2, 4, 8, 16), (1, 2, 4, 8, 16))),
            _s(SMFEM_QUAD9, *grid("dome", _r(1, 2, 4), (1, 2, 4, 8))),
            _s(REF2D, *grid("dome", _r(1, 2, 4, 8), (1, 2, 4, 8))),
            _s(REF3D, *grid("dome", _r(1), (1, 2, 4)), *grid("dome", _r(2), (1, 2, 4))),
            explicit_3d(),
            *calculix(explicit=False),  # axisymmetric: ccx's explicit increment collapses at the axis
        ), reference=(REF2D, {"refine": 16}), truth=TruthPlan(MODAL_TRUTH, refine=(2, 4, 8))),
        CaseStudy("thick_cylinder", (
            _s(SMFEM, *grid("thick_cylinder", ({"harmonics": 20}, {"refine": 2, "harmonics": 40},
                                               {"refine": 4, "harmonics": 80}, {"refine": 8, "harmonics": 160}),
                            (1, 2, 4, 8, 16, 32, 64))),
            _s(SMFEM_QUAD9, *grid("thick_cylinder", ({"harmonics": 20}, {"harmonics": 40}, {"harmonics": 80},
                                                     {"refine": 2, "harmonics": 80}), (1, 4, 16, 32, 64)),
               *grid("thick_cylinder", ({"harmonics": 40, "time_scheme": "gauss"},
                                        {"harmonics": 80, "time_scheme": "gauss"}), (1, 2, 4))),
            _s(REF2D, *grid("thick_cylinder", _r(1, 2), (1, 2, 4, 8, 16, 32)), *grid("thick_cylinder", _r(3), (1, 4, 16))),
            # 3D to 1 % (2026-11-26, against the stored truth, B_ut the worst): r1 dt/16 1.8 %, r2
            # dt/16 1.13 %, dt/32 1.15 % (its mesh's limit), r3 dt/32 0.81 % (202 CPU s)
            _s(REF3D, *grid("thick_cylinder", _r(1), (1, 2, 4, 8)), *grid("thick_cylinder", _r(2), (1, 2, 4, 16)),
               *grid("thick_cylinder", _r(3), (16, 32))),
            explicit_3d(),
            *calculix(),
        ), reference=(REF2D, {"refine": 4}),
            truth=TruthPlan(MODAL_TRUTH, refine=(4, 8, 16), harmonics=(320, 640, 1280))),
        CaseStudy("notched_cylinder", (
            # B-bar, and far in mesh and harmonics: the error converges at about first order in
            # both (docs/scenes.md, section 3; r16 H160 dt / 2 2.29 % in 85 CPU s, 2.1 GB, factorized
            # whole past the default limit: the matrix-free path takes over 15 minutes there)
            _s(SMFEM, *grid("notched_cylinder", ({"harmonics": 40}, {"refine": 2, "harmonics": 80},
                                                 {"refine": 4, "harmonics": 160}, {"refine": 8, "harmonics": 160},
                                                 {"refine": 16, "harmonics": 160}), (1, 2)),
               bbar=True, direct_max_nonzeros=10**8),
            _s(SMFEM_QUAD9, *grid("notched_cylinder", ({"harmonics": 80}, {"refine": 2, "harmonics": 80},
                                                       {"refine": 3, "harmonics": 80}, {"refine": 4, "harmonics": 80},
                                                       {"refine": 2, "harmonics": 160}), (1, 2)), bbar=True),
            # the 2D reference with B-bar too (standard: r1 6.5 %, r2 4.3 %; B-bar r1 4.3 %, r2 2.9 %)
            _s(REF2D, *grid("notched_cylinder", _r(1, 2, 3, 4, 6), (1, 2)), bbar=True),
            # 3D with B-bar elements (the standard 27-node element locks in the plastic flow:
            # against the stored truth at dt r1 8.2, r2 5.2, r3 4.2 % without, r1 5.0, r2 3.4, r3
            # 3.02 % with (193 CPU s); r3 dt / 2 2.70 % (270 s): the 3 %)
            _s(REF3D, *grid("notched_cylinder", _r(1), (0.5, 1, 2, 4)), *grid("notched_cylinder", _r(2, 3), (1, 2)),
               bbar=True),
            explicit_3d(bbar=True),
            *calculix(modal=False),
        ), reference=(REF2D, {"refine": 3}),
            truth=explicit_truth(bbar=True)),
        CaseStudy("notched_strip", (
            _s(SMFEM, *grid("notched_strip", ({"harmonics": 80}, {"harmonics": 120}, {"harmonics": 160},
                                              {"harmonics": 240}, {"harmonics": 400}), (1, 2, 4, 8))),
            _s(SMFEM_QUAD9, *grid("notched_strip", ({"harmonics": 120, "coarsen": 2}, {"harmonics": 120},
                                                    {"harmonics": 240}), (0.5, 1, 2))),
            # its tangents factorized, as in the quick report
            _s(REF2D, *grid("notched_strip", _r(1), (1, 2, 4, 8)), *grid("notched_strip", _r(2), (1, 2, 4)),
               linear_solver="superlu"),
            # 3D to 1 %: r1 2.3 % at every dt (its mesh), r2 dt 1.25 %, dt/2 0.96 % (146 CPU s)
            _s(REF3D, *grid("notched_strip", _r(1), (0.5, 1, 2, 4)), *grid("notched_strip", _r(2), (1, 2))),
            explicit_3d(bbar=True),
            *calculix(modal=False),
        ), reference=(REF2D, {"refine": 3}, (("linear_solver", "superlu"),)),
            truth=explicit_truth(bbar=True)),
        CaseStudy("rod_impact", (
            _s(SMFEM, *grid("rod_impact", _r(1, 2, 4, 8), (1, 2, 4, 8))),
            _s(SMFEM_QUAD9, *grid("rod_impact", _r(1, 2, 4), (1, 2, 4, 8))),
            _s(REF2D, *grid("rod_impact", _r(1, 2, 4), (1, 2, 4, 8))),
            _s(REF3D, *grid("rod_impact", _r(1), (0.5, 1, 2, 4))),
            explicit_3d(),
            *calculix(explicit=False, modal=False),
        ), reference=(REF2D, {"refine": 8}),
            truth=explicit_truth()),
        # contact between bodies: CalculiX refused (its contact pairs stop: the report says why)
        CaseStudy("ring_in_ring", (
            _s(SMFEM, *grid("ring_in_ring", ({"harmonics": 20}, {"refine": 2, "harmonics": 20}, {"harmonics": 40}),
                            (1, 2, 4, 8, 16))),
            _s(SMFEM_QUAD9, *grid("ring_in_ring", ({"harmonics": 20}, {"harmonics": 40}), (2, 4, 8, 16))),
            _s(REF2D, *grid("ring_in_ring", _r(1, 2), (1, 2, 4, 8, 16))),
            _s(REF3D, *grid("ring_in_ring", _r(1), (1, 2, 4, 8))),
            explicit_3d(),
            *calculix(explicit=False, modal=False),
        ), reference=(REF2D, {"refine": 3}),
            truth=RING_TRUTH),
        CaseStudy("rod_collision", (
            _s(SMFEM, *grid("rod_collision", _r(1, 2, 4), (1, 2, 4, 8))),
            _s(SMFEM_QUAD9, *grid("rod_collision", _r(1, 2), (1, 2, 4, 8))),
            _s(REF2D, *grid("rod_collision", _r(1, 2, 4), (1, 2, 4, 8))),
            *calculix(explicit=False, modal=False),
        ), reference=(REF2D, {"refine": 4}),
            truth=explicit_truth(), left_out=((REF3D, ROD_COLLISION_3D),)),
        CaseStudy("layered_cylinder", (
            _s(SMFEM, *grid("layered_cylinder", ({"harmonics": 20}, {"refine": 2, "harmonics": 40},
                                                 {"refine": 4, "harmonics": 80}), (1, 2, 4, 8, 16))),
            # time-limited as the thick cylinder: the order-4 Gauss scheme too (the thick cylinder's 1 %)
            _s(SMFEM_QUAD9, *grid("layered_cylinder", ({"harmonics": 40},), (4, 16)),
               *grid("layered_cylinder", ({"harmonics": 80},), (16, 32, 64)),
               *grid("layered_cylinder", ({"harmonics": 80, "time_scheme": "gauss"},
                                          {"refine": 2, "harmonics": 80, "time_scheme": "gauss"}), (1, 2, 4))),
            _s(REF2D, *grid("layered_cylinder", _r(1, 2), (1, 2, 4, 8, 16))),
            _s(REF3D, *grid("layered_cylinder", _r(1), (1, 2, 4))),
            explicit_3d(),
            *calculix(),
        ), reference=(REF2D, {"refine": 4}),
            truth=TruthPlan(MODAL_TRUTH, refine=(4, 8, 16), harmonics=(320, 640, 1280))),
        CaseStudy("flywheel", (
            _s(SMFEM, *grid("flywheel", ({}, {"refine": 2}), (0.5, 1, 2, 4, 8))),
            _s(SMFEM_QUAD9, *grid("flywheel", ({},), (1, 2, 4))),
            # 3D: the mirror half (FLYWHEEL_3D), the implicit engine only (FLYWHEEL_EXPLICIT). No
            # CalculiX: on the whole's 8-round mesh ccx
            # takes 49 CPU s a step (two SPOOLES factorizations each), 500 steps (docs/scenes.md)
            _s(REF3D, *FLYWHEEL_3D, until=FLYWHEEL_3D_UNTIL),
        ), reference=None,
            truth=FLYWHEEL_TRUTH, left_out=((REF3D_EXPLICIT, FLYWHEEL_EXPLICIT),)),
        CaseStudy("layered_cylinder_pulse", (
            _s(SMFEM, *grid("layered_cylinder_pulse", ({"harmonics": 20}, {"refine": 2, "harmonics": 40},
                                                       {"refine": 4, "harmonics": 80}), (1, 2, 4, 8, 16))),
            _s(SMFEM_QUAD9, *grid("layered_cylinder_pulse", ({"harmonics": 40},), (4, 16)),
               *grid("layered_cylinder_pulse", ({"harmonics": 80}, {"harmonics": 160}), (16, 32, 64))),
            _s(REF2D, *grid("layered_cylinder_pulse", _r(1, 2), (1, 2, 4, 8, 16))),
            explicit_3d(),
            *calculix(),
        ), reference=(REF2D, {"refine": 4}),
            truth=TruthPlan(MODAL_TRUTH, refine=(4, 8, 16), harmonics=(320, 640, 1280))),
        CaseStudy("moving_load", (
            _s(SMFEM, *grid("moving_load", ({"harmonics": 20}, {"harmonics": 60}, {"harmonics": 120},
                                            {"refine": 2, "harmonics": 240}), (0.5, 1, 2, 4, 8))),
            _s(SMFEM_QUAD9, *grid("moving_load", ({"harmonics": 120},), (1, 2, 4, 8))),
            _s(REF2D, *grid("moving_load", _r(1, 2, 4), (1, 2, 4, 8))),
            _s(REF3D, *grid("moving_load", _r(1), (1, 2))),
            explicit_3d(),
            *calculix(),
        ), reference=(REF2D, {"refine": 4}),
            truth=TruthPlan(MODAL_TRUTH, refine=(2, 4, 8), harmonics=(120, 240, 480))),
        CaseStudy("moving_load_notched", (
            # the notch is a step in the stiffness along the span: harmonics and the section's
            # element, not dt, hold SMFEM's error (dt / 2 moves it 0.3 %)
            _s(SMFEM, *grid("moving_load_notched", ({"harmonics": 120}, {"harmonics": 240},
                                                    {"refine": 2, "harmonics": 240}, {"refine": 2, "harmonics": 480}),
                            (1, 2))),
            _s(SMFEM_QUAD9, *grid("moving_load_notched", ({"harmonics": 120}, {"harmonics": 240}, {"harmonics": 480}),
                                  (1, 2))),
            _s(REF2D, *grid("moving_load_notched", _r(1), (1, 2, 4)), *grid("moving_load_notched", _r(2), (1, 2)),
               {"refine": 3}),
            _s(REF3D, *grid("moving_load_notched", _r(1), (1,))),
            explicit_3d(bbar=True),
        ), reference=(REF2D, {"refine": 3}),
            truth=explicit_truth(MOVING_NOTCHED_LADDER, bbar=True)),
    )


def _estimated(*studies: CaseStudy, unestimated=(), smfem_only=()) -> tuple[CaseStudy, ...]:
    """``studies`` with their error estimates measured for :data:`ESTIMATED_SERIES`, but none for
    ``unestimated`` (the quick report's flywheel: its three settings' estimates cost 290 CPU s,
    its refine-2 companion split 4 x 4; ring_in_ring's 34 CPU s, its reference's refine-2
    companion 22 s; the full report measures them) and SMFEM's only for ``smfem_only`` (the
    quick report's notched strip: the reference's refine-2 setting alone is 112-207 CPU s)."""
    return tuple(replace(s, estimated=() if s.case in unestimated else (SMFEM,) if s.case in smfem_only
                         else ESTIMATED_SERIES) for s in studies)


def select(plan: tuple[CaseStudy, ...], names) -> tuple[CaseStudy, ...]:
    """The case studies of ``names`` (all when empty), in the order given (a scene file's:
    :func:`smfem.studies.own_scene.select`)."""
    if not names:
        return plan
    by_name = {s.case: s for s in plan}
    unknown = [n for n in names if n not in by_name]
    if unknown:
        raise ParameterError(f"unknown case {unknown[0]!r}: choose one of {', '.join(by_name)} or give a scene "
                             "file NAME.toml")
    return tuple(by_name[n] for n in names)


def with_solvers(plan: tuple[CaseStudy, ...], solvers) -> tuple[CaseStudy, ...]:
    """``plan`` with only the series of ``solvers`` (all when empty), and the same-dt reference
    run and error estimates where their solver is among them: SMFEM against one competitor
    without the hours of the others (``smfem study --solvers``)."""
    if not solvers:
        return plan
    known = sorted({s.solver for study in plan for s in study.series})
    unknown = [n for n in solvers if n not in known]
    if unknown:
        raise ParameterError(f"no series of solver {unknown[0]!r} in this study: choose among {', '.join(known)}")
    return tuple(replace(study, series=tuple(s for s in study.series if s.solver in solvers),
                         reference=study.reference if study.reference and study.reference[0] in solvers else None,
                         estimated=tuple(e for e in study.estimated if e in solvers)) for study in plan)
