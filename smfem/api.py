"""The Python interface: what the command line does, as functions (``import smfem``).

>>> import smfem
>>> case = smfem.load("thick_cylinder", t_end=2e-4)        # a built-in scene, a .toml file or a Case
>>> run = smfem.run(case)                                   # SMFEM, with its error estimate
>>> run.history.columns.tolist()                            # a pandas DataFrame: t and each probe
['t', 'A_ur', 'B_ut', 'C_ur']
>>> ref = smfem.run(case, solver="reference-2d", estimate=False)
>>> smfem.compare(run, ref).probe.tolist()                  # per probe, the relative difference
['A_ur', 'B_ut', 'C_ur']

Parameters of the scene and options of the solver go in as keywords, as ``--set`` does on the
command line (docs/contract.md); a value out of range raises :class:`cases.ParameterError` with
the sentence the command line prints. Every run pins the numerics to one BLAS thread (set
``SMFEM_THREADS`` before the first import to measure another count), so CPU times compare.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import meshio
import numpy as np
import pandas as pd

from cases import Case, ParameterError, get_case, rebuild
from cases.result import RunResult
from smfem.runs import threads, validity
from smfem.runs.errors import probe_error
from smfem.runs.estimate import estimate as estimate_error
from smfem.runs.estimate import headline as estimate_headline
from smfem.runs.files import add_to_summary, read_run, summary, write_run
from smfem.runs.progress import Progress
from smfem.runs.registry import SMFEM, family, lookup
from smfem.runs.registry import solve as solve_with
from smfem.runs.registry import solvers as registered
from smfem.studies.timing import BUDGET_S as TIMING_BUDGET_S

__all__ = ["Result", "compare", "error", "load", "read", "report", "run", "scenes", "solvers", "study", "truth"]

#: parameters that choose the discretization, not the problem (a stored truth holds for any)
DISCRETIZATION = ("refine", "coarsen", "harmonics", "dt", "tol", "dim", "element", "time_scheme")


def scenes() -> list[str]:
    """Names of the built-in scenes (docs/scenes.md); any ``.toml`` scene file runs as well."""
    from cases import CASES, VARIANTS

    return [*CASES, *VARIANTS]


def solvers() -> list[str]:
    """Names of the solvers :func:`run` takes (``smfem``, ``smfem-quad9``, ``reference-2d``, ...)."""
    return [s.name for s in registered()]


def load(scene: str | Path | Case, **params) -> Case:
    """A scene as a :class:`cases.Case`.

    Parameters
    ----------
    scene : str, Path or Case
        a built-in scene's name (:func:`scenes`), a scene file ``*.toml`` (docs/scenes.md,
        "Scenes from a file") or a case built already
    **params
        the scene's parameters (``dt`` in s, ``refine``, ``harmonics``, ``t_end`` in s, ...:
        ``smfem cases NAME`` lists them with their ranges)

    Raises
    ------
    cases.ParameterError
        for an unknown scene, key or a value out of range
    """
    if isinstance(scene, Case):
        return rebuild(scene, params) if params else scene
    return get_case(scene, params)


@dataclass
class Result:
    """One finished run.

    Attributes
    ----------
    case : the :class:`cases.Case` it ran
    solver : the solver's name
    raw : the solver's :class:`cases.result.RunResult` (arrays as computed)
    wall_time_s : wall time of the run alone (companions not counted), s
    error_estimate : the run's estimated error (companion runs: coarser mesh, twice the step,
        half the harmonics; see ``docs/contract.md``) as ``summary.json`` holds it, or None
    """

    case: Case
    solver: str
    raw: RunResult
    wall_time_s: float = math.nan
    error_estimate: dict | None = None
    extra: dict = field(default_factory=dict)

    @property
    def history(self) -> pd.DataFrame:
        """Probe histories: column ``t`` (s) and one column per probe (SI units: m, m/s, Pa)."""
        n = len(self.raw.t)
        return pd.DataFrame({"t": self.raw.t, **{k: np.asarray(v)[:n] for k, v in self.raw.history.items()}})

    @property
    def summary(self) -> dict:
        """What ``summary.json`` holds: settings, dof, steps, CPU time (s), iterations, validity."""
        extra = {"error_estimate": self.error_estimate} if self.error_estimate else {}
        checked = self.extra.get("validity")
        return {**summary(self.case, family(self.solver), self.raw, self.wall_time_s, checked), **self.extra, **extra}

    @property
    def cpu_time_s(self) -> float:
        """CPU time of the solve (one BLAS thread), s."""
        return self.raw.cpu_time_s

    @property
    def estimate(self) -> float:
        """The estimated relative error of the run's worst displacement or velocity probe (NaN
        without an estimate)."""
        top = estimate_headline(self.case, self.error_estimate) if self.error_estimate else None
        return top[1] if top else math.nan

    @property
    def mesh(self) -> meshio.Mesh | None:
        """The 3D field at the last step (displacement, stress, plastic strain) as a meshio mesh,
        or None for a run without fields."""
        return self.raw.mesh

    def to_pyvista(self):
        """The last step's field as a ``pyvista.UnstructuredGrid`` (pyvista is imported here only)."""
        import pyvista

        if self.raw.mesh is None:
            raise ValueError(f"{self.case.name} ({self.solver}): run without fields (fields=False)")
        return pyvista.from_meshio(self.raw.mesh)

    def write(self, out: str | Path) -> Path:
        """Write the run as ``smfem run`` does (history.csv, summary.json, fields.vtu; docs/contract.md)."""
        out = Path(out)
        extra = {**self.extra, **({"error_estimate": self.error_estimate} if self.error_estimate else {})}
        write_run(out, self.case, family(self.solver), self.raw, self.wall_time_s, extra=extra)
        return out


def run(scene: str | Path | Case, solver: str = SMFEM, *, estimate: bool = True, fields: bool = True,
        every: int = 0, progress: bool = False, out: str | Path | None = None, **params) -> Result:
    """Run a scene with one solver.

    Parameters
    ----------
    scene : str, Path or Case
        as :func:`load` takes it
    solver : str
        one of :func:`solvers` (default ``"smfem"``)
    estimate : bool
        also estimate the run's error from companion runs (about 1-4 times the run's CPU time);
        solvers without an estimate (modal, CalculiX) skip it
    fields : bool
        keep the 3D field of the last step (:attr:`Result.mesh`)
    every : int
        also keep the field every ``every`` steps (``raw.frames``; written as ``fields.pvd``)
    progress : bool
        a progress bar on the terminal
    out : str or Path, optional
        also write the run there as ``smfem run`` does (written before the companions start)
    **params
        the scene's parameters (:func:`load`) and the solver's options (SMFEM's ``bbar``,
        ``linear_solver``, ...: the names of its entry in ``smfem.runs.registry``)

    Returns
    -------
    Result
    """
    entry = lookup(solver)
    own = entry.options()
    given = {k: params.pop(k) for k in list(params) if k in own}
    case = load(scene, **params)
    try:
        options = entry.make_options(given) if given else None
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"{solver} options: {exc}") from None
    threads.pin()
    extra = {"options": given} if given else {}
    wall0 = time.perf_counter()
    raw = _solve(solver, case, f"{case.name} ({solver})", progress, fields=fields, every=every, options=options)
    result = Result(case, solver, raw, time.perf_counter() - wall0, None, {"validity": validity.check(case, raw), **extra})
    if out is not None:
        result.write(out)
    if estimate and raw.converged and entry.estimated:
        est = estimate_error(case, solver, raw, run=lambda s, companion: _solve(
            s, companion, f"{companion.name} ({s}, error-estimate companion)", progress, options=options))
        result.error_estimate = est = claimed(result.extra["validity"], est)
        if out is not None:
            add_to_summary(Path(out), {"error_estimate": est})
    return result


def claimed(check: dict, est: dict) -> dict:
    """No accuracy claimed for a run outside the small-strain model (``check``: its validity):
    its companions measure the discretization of a model that does not hold."""
    return est if check["valid"] else {**est, "claim": "none: the run is outside the small-strain model (validity)"}


def _solve(solver: str, case: Case, title: str, progress: bool, **options) -> RunResult:
    bar = Progress(case.n_steps, title, "step", enabled=progress, leave=False)
    try:
        return solve_with(solver, case, progress=lambda step, n: bar.update(step), **options)
    finally:
        bar.close()


def read(path: str | Path, fields: bool = True, scene: str | Path | Case | None = None) -> Result:
    """A run written by ``smfem run`` or :meth:`Result.write`, read back; ``scene``: the scene it
    ran (default: the built-in scene of its name; give the file for a scene from a file), at
    the parameters the run's summary.json records."""
    raw, written = read_run(Path(path), fields=fields)
    params = dict(written["params"])
    if scene is None:
        case = get_case(written["case"], _overrides(written["case"], params))
    else:
        base = load(scene)
        case = load(base, **{k: v for k, v in params.items() if base.params.get(k) != v})
    extra = {k: written[k] for k in ("validity", "options") if k in written}
    return Result(case, written["solver"], raw, float(written.get("wall_time_s", math.nan)),
                  written.get("error_estimate"), extra)


def _overrides(name: str, params: dict) -> dict:
    """The parameters of ``params`` that differ from scene ``name``'s defaults."""
    defaults = get_case(name).params
    return {k: v for k, v in params.items() if defaults.get(k) != v}


def compare(result: Result, against: Result) -> pd.DataFrame:
    """Per probe shared by both runs, ``result``'s relative difference from ``against``: the
    max-norm of the history difference over the max of ``against`` (through the scene's
    comparison window), or the relative difference of the peaks for plastic strains.

    Returns
    -------
    pandas.DataFrame with columns ``probe``, ``measure``, ``difference`` (a fraction)
    """
    window = result.case.references.get("comparison_window_s", 0.0)
    rows = []
    for name in (p.name for p in result.case.probes):
        if name in result.raw.history and name in against.raw.history:
            measure, value = probe_error(name, result.raw.t, np.asarray(result.raw.history[name]), against.raw.t,
                                         np.asarray(against.raw.history[name]), window)
            rows.append({"probe": name, "measure": measure, "difference": value})
    return pd.DataFrame(rows, columns=["probe", "measure", "difference"])


def truth(scene: str | Case):
    """The stored truth of a built-in scene (``smfem/truths/NAME``: converged histories and
    their uncertainty, :class:`smfem.studies.truth.Truth`), or None: no truth is stored for it,
    or ``scene`` is a case whose physics (load, material, window: every parameter but the
    discretization's) differ from the truth's, or a scene from a file."""
    from smfem.studies.stored import directory, read as read_truth

    case = scene if isinstance(scene, Case) else load(scene)
    path = directory(case.name)
    if case.source is not None or not (path / "summary.json").exists():
        return None
    stored = read_truth(path)
    physics = lambda params: {k: v for k, v in params.items() if k not in DISCRETIZATION}
    return None if stored.params and physics(stored.params) != physics(case.params) else stored


def error(result: Result, against=None) -> float:
    """The run's total error: the largest relative max-norm error over its displacement and
    velocity probes against ``against`` (a :class:`~smfem.studies.truth.Truth`; default: the
    stored truth, :func:`truth`), the measure of the report's headline.

    Raises
    ------
    ValueError
        without a truth to measure against
    """
    from smfem.studies.metrics import headline_error

    against = truth(result.case) if against is None else against
    if against is None:
        raise ValueError(f"{result.case.name}: no stored truth of this scene at these parameters")
    return headline_error(result.case, against, result.raw.t, result.raw.history)


def study(scenes: list[str] | tuple[str, ...], out: str | Path = "out/study", *, full: bool = False,
          workers: int = 2, progress: bool = True, cache: str | Path | None = None, scheduler: str | None = None,
          timing_budget_s: float | None = TIMING_BUDGET_S, solvers: tuple[str, ...] = ()):
    """Series of runs of ``scenes`` (built-in names, or scene files ``*.toml``: a study made for
    each, :mod:`smfem.studies.own_scene`) with every solver (``solvers``: only these), their
    errors against the truth and the work-precision diagrams, as ``smfem study`` makes them
    (``out/tables/*.csv``, ``out/figures/``). Returns the :class:`reports.build.Report`: ``tables`` (name -> DataFrame),
    ``analyses`` (per scene), ``study`` (executed and cached runs). ``cache``: the run cache
    (default ``out/runs``; a run found there is read, not run); ``scheduler``: a dask
    scheduler's address (``tcp://host:8786``) to run on instead of ``workers`` local processes.
    After the runs, the timing pass times the runs behind the headline again (:mod:`reports.timing`;
    ``tables/timing.csv``); ``timing_budget_s``: the CPU s it may spend on a second timing of runs
    over a minute; None: no pass, the study's single-shot CPU times."""
    return _build(tuple(scenes), out, full, workers, progress, False, cache, scheduler, timing_budget_s,
                  solvers=tuple(solvers))


def report(out: str | Path = "out/report", *, full: bool = False, scenes: tuple[str, ...] = (), workers: int = 2,
           progress: bool = True, cache: str | Path | None = None, scheduler: str | None = None,
           timing_budget_s: float | None = TIMING_BUDGET_S, retime: bool = False):
    """The verification report (``index.html``, ``report.pdf``, ``tables/``, ``figures/``) as
    ``smfem report`` makes it; ``scenes``: a part of the plan (default: all); the rest as
    :func:`study`. ``retime``: redo only the timing pass on an earlier report of the same scenes
    and settings in ``out`` (its run cache: a missing run raises
    :class:`smfem.studies.study.NotInCache`) and write its tables and document again. Returns the
    :class:`reports.build.Report`."""
    return _build(tuple(scenes), out, full, workers, progress, True, cache, scheduler, timing_budget_s, retime)


def _build(names: tuple[str, ...], out, full: bool, workers: int, progress: bool, document: bool, cache, scheduler,
           timing_budget_s: float | None, retime: bool = False, solvers: tuple[str, ...] = ()):
    from reports.build import build
    from smfem.studies.own_scene import select
    from smfem.studies.plan import full as full_plan, quick, with_solvers
    from smfem.studies.timing import TimingRule

    threads.pin()
    plan = with_solvers(select(full_plan() if full else quick(), names, full), solvers)
    timing = None if timing_budget_s is None else TimingRule.of(full, timing_budget_s, retime)
    return build(plan, Path(out), cache=cache and Path(cache), scheduler=scheduler, workers=workers,
                 progress=progress, settings="full" if full else "quick", document=document, timing=timing,
                 retime=retime)
