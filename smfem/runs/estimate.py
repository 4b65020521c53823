"""An error estimate for one run, split into space, harmonics and time, from cheap companions.

Each part compares two runs that differ in one parameter and turns their difference into the
finer one's error (Richardson): ``e = d / (ratio ** p - 1)``, where ``d`` is the difference
measured as every comparison of the project measures it (:func:`smfem.runs.errors.probe_error`: the
relative max-norm over the window, through the case's comparison window; the relative peak
difference for plastic strains), ``ratio`` how much finer the finer run is, and ``p`` the order.

The companions are cheap next to the run:
- space: the same run on a mesh half as fine (``refine / 2``, or ``coarsen = 2`` at an odd
  refine): a quarter of a 2D section's unknowns. Its order is the one the elements have
  (:data:`ORDERS`); where a cut-out's re-entrant corners or plasticity are in the body, the
  lowest order believed (:data:`SINGULAR_SPACE_ORDER`). A third, coarser mesh does not observe
  it there: on the notched strip the 2D reference's meshes a half and a quarter of the paper's
  show order 2, while its paper mesh is only 1.85 times more accurate than the half one (the
  estimate fell to half the actual error); the first order errs on the safe side;
- time: that coarse mesh at twice and four times the step, and
- harmonics (SMFEM, unless the scene is axisymmetric): that coarse mesh at half and a quarter
  of the harmonics. With three levels the order is observed, per probe, and kept within
  :data:`OBSERVED_RANGE`; where the three levels do not converge on a displacement or
  velocity probe (the notched strip's notch at 60 and 30 harmonics; a wave at four times the
  step), that part is measured against a finer companion instead (half the step, half as many
  harmonics again) at the scheme's order (:data:`ORDERS`; in time 4 for SMFEM's opt-in
  ``time_scheme=gauss``, :func:`order`): the run and that companion are the
  finest pair, and the pair the coarser ones were not. Where that part's safe reading (the
  lowest order, from its coarser pair) raises the run's estimate by little (:data:`NEGLIGIBLE`),
  it is kept: the finer companion would cost more than the run to lower a part that does not
  decide the total.
Time and harmonics are measured on the coarse mesh: their errors come from the load's and the
response's low modes, which the coarse mesh carries as the fine one does, and those companions
cost an eighth to a sixteenth of the run each. A halved mesh keeps the cut-outs' edges as
nodes (the notched strip's notch, 2.5 elements deep at half its paper mesh, would otherwise
become another body). The total is the sum of the parts: they may cancel in the run; the
estimate does not count on it.

The estimate serves the run, never the other way round: a companion whose settings leave a
parameter's range (twice the step above the largest ``dt``, a mesh that cannot be halved) is
moved to the finer side or left out, one that fails or does not converge leaves its part out,
and the estimate says which parts it could not measure (``partial``, ``unmeasured``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cases import ParameterError, rebuild
from cases.params import failure, one_line

from .errors import probe_error
from .registry import lookup, solve, solvers

#: the order of each part's error in its parameter (h, 1/harmonics, dt) where no third level
#: observes it: Newmark's average acceleration is second order in dt, both elements second order
#: in h in the displacements, a patch load's Fourier series second order in the response
ORDERS = {"space": 2.0, "harmonics": 2.0, "time": 2.0}
#: the time order of SMFEM's opt-in scheme ``time_scheme=gauss`` (2-stage Gauss-Legendre)
GAUSS_TIME_ORDER = 4.0
#: space with a re-entrant corner (a cut-out) or a plastic hinge: first order (the explicit
#: truth ladders observe 0.7 ... 1.1 on the notched cylinder)
SINGULAR_SPACE_ORDER = 1.0
#: observed orders are kept within these: below 1 a difference is not yet a convergence, above
#: 2 neither scheme converges so fast (in time: the scheme's order, :func:`order`), and the
#: estimate must not shrink on a lucky cancellation
OBSERVED_RANGE = (1.0, 2.0)
#: a pre-asymptotic part whose safe reading (the lowest order, from its coarser pair) raises the
#: run's estimated error (the largest over its displacement and velocity probes) by at most this
#: fraction is kept as read: a finer companion (half the step on the coarse mesh, dearer than
#: the run at a fine step) would only lower a part that does not decide the estimate
NEGLIGIBLE = 0.25
#: the parts a run's error is split into
PARTS = ("space", "harmonics", "time")


@dataclass(frozen=True)
class Companion:
    """One companion run: its parameter overrides, and which run it is compared with."""

    name: str  # a part, its third level ("time2", "harmonics2") or its finer side ("time_up", ...)
    overrides: dict
    against: str  # "run" or another companion's name

    @property
    def part(self) -> str:
        return self.name.removesuffix("2").removesuffix("_up")


@dataclass(frozen=True)
class Plan:
    """A run's companions, the parts measured on the finer side from the start (part ->
    companion: twice the step leaves the range, one harmonic cannot be halved) and the parts
    no companion can measure (part -> why)."""

    companions: list[Companion]
    upward: dict[str, str]
    unmeasured: dict[str, str]


#: a halved mesh must be at least this much coarser to measure space: a section whose
#: segments have one element each cannot be halved (``coarsen`` keeps one per segment)
MIN_SPACE_RATIO = 1.25


def admissible(case, overrides: dict) -> bool:
    """Whether ``case`` with ``overrides`` is a valid case: twice the step of a run at the
    largest ``dt``, or ``coarsen`` past its range, is not one."""
    try:
        rebuild(case, overrides)
    except ParameterError:
        return False
    return True


def plan(case, solver: str, on_coarse: bool = True) -> Plan:
    """The companion runs of ``case`` for ``solver`` (an ``estimated`` one of
    :mod:`smfem.runs.registry`, else none: time-stepping on a mesh; the modal truth is exact in time,
    the explicit engine sets its own step, CalculiX meshes on its own): the coarse mesh, and on
    it (``on_coarse``; else on the run's own mesh) twice and four times the step and (a solver
    with harmonics) half and a quarter of the harmonics, the third levels observing the orders.
    Both solvers keep the cut-outs' edges as grid nodes at any mesh, so the coarse mesh is the
    same body. A companion outside the parameters' ranges is never planned: time and harmonics
    move to the finer side (half the step, two harmonics), space is left out, and the plan
    says why."""
    entry = lookup(solver)
    if not entry.estimated:
        return Plan([], {}, {})
    out, upward, unmeasured = [], {}, {}
    base, against = {}, "run"
    if on_coarse:
        coarse = halved(case)
        settings = ", ".join(f"{k} {v}" for k, v in coarse.items())
        if "coarsen" in coarse and case.section.kind == "mesh":  # a mesh cannot be coarsened: twice as fine
            _upward(case, "space", {}, "run", out, upward, unmeasured)
        elif not admissible(case, coarse):
            unmeasured["space"] = f"half the mesh ({settings}) is outside the parameters' range"
        elif space_ratio(case, rebuild(case, coarse)) < MIN_SPACE_RATIO:
            unmeasured["space"] = f"the mesh cannot be halved ({settings} leaves one element per segment)"
        else:
            out.append(Companion("space", coarse, "run"))
            base, against = coarse, "space"
    if case.n_steps >= 2 and admissible(case, {**base, "dt": 2 * case.dt}):  # twice the step fits the window
        out.append(Companion("time", {**base, "dt": 2 * case.dt}, against))
        if case.n_steps >= 4 and admissible(case, {**base, "dt": 4 * case.dt}):
            out.append(Companion("time2", {**base, "dt": 4 * case.dt}, "time"))
    else:
        _upward(case, "time", base, against, out, upward, unmeasured)
    if entry.harmonics and not case.axisymmetric:
        if case.harmonics > 1:
            out.append(Companion("harmonics", {**base, "harmonics": max(1, case.harmonics // 2)}, against))
            if case.harmonics >= 4:
                out.append(Companion("harmonics2", {**base, "harmonics": case.harmonics // 4}, "harmonics"))
        else:
            _upward(case, "harmonics", base, against, out, upward, unmeasured)
    return Plan(out, upward, unmeasured)


def _upward(case, part: str, base: dict, against: str, out: list, upward: dict, unmeasured: dict) -> None:
    """Plan ``part`` on the finer side (its coarser side is out of range), or say why not."""
    c = finer_companion(case, part, base, against)
    if admissible(case, c.overrides):
        out.append(c)
        upward[part] = c.name
    else:
        unmeasured[part] = "neither a coarser nor a finer companion is within the parameters' range"


def companions(case, solver: str) -> list[Companion]:
    """The companion runs of ``case`` for ``solver`` (:func:`plan`)."""
    return plan(case, solver).companions


def halved(case) -> dict:
    """The overrides of a mesh half as fine as the case's: ``refine`` halved where it is even,
    else ``coarsen`` doubled."""
    refine, coarsen = case.refine, case.params.get("coarsen", 1)
    return {"refine": refine // 2} if refine % 2 == 0 else {"coarsen": 2 * coarsen}


def space_order(case) -> float:
    """The space order assumed: :data:`ORDERS`, first order with cut-outs or plasticity."""
    return SINGULAR_SPACE_ORDER if case.cutouts or case.material.plastic else ORDERS["space"]


def order(case, part: str) -> float:
    """The order of ``part`` where no third level observes it (:data:`ORDERS`): in time the
    scheme's, :data:`GAUSS_TIME_ORDER` for an SMFEM run with ``time_scheme=gauss``."""
    if part == "time" and case.params.get("time_scheme") == "gauss":
        return GAUSS_TIME_ORDER
    return ORDERS[part]


def space_ratio(fine, coarse) -> float:
    """How much finer the mesh of ``fine`` is than that of ``coarse``: the geometric mean over
    the section's refinable axes of the element-count ratios."""
    if fine.section.kind == "mesh":  # split k x k: k times the elements along each direction
        return fine.mesh_scale / coarse.mesh_scale
    (fs, ft), (cs, ct) = fine.cutout_edges, coarse.cutout_edges
    ratios = [(len(fa.grid(fine.mesh_scale, fe)) - 1) / (len(ca.grid(coarse.mesh_scale, ce)) - 1)
              for fa, ca, fe, ce in ((fine.section.s, coarse.section.s, fs, cs), (fine.section.t, coarse.section.t, ft, ct))
              if fa.refinable]
    return float(np.exp(np.mean(np.log(ratios)))) if ratios else 1.0


def _ratio(part: str, a, b) -> float:
    """How much finer run ``a`` is than run ``b`` in ``part``'s parameter."""
    if part.startswith("time"):
        return b.dt / a.dt
    if part.startswith("harmonics"):
        return a.harmonics / b.harmonics
    return space_ratio(a, b)


def _differences(case, a, b) -> dict[str, float]:
    """|difference| per probe of two results, as every comparison measures it (relative to ``a``)."""
    window = case.references.get("comparison_window_s", 0.0)
    return {name: abs(probe_error(name, b.t, b.history[name], a.t, values, window)[1])
            for name, values in a.history.items() if name in b.history}


def observed_order(d_fine: float, d_coarse: float, ratio: float, highest: float = OBSERVED_RANGE[1]) -> float:
    """The order two successive differences show, within :data:`OBSERVED_RANGE` (the range's
    low end when they do not fall; ``highest``: the scheme's order where it exceeds the range)."""
    if not (d_fine > 0 and d_coarse > d_fine and ratio > 1):
        return OBSERVED_RANGE[0]
    return float(np.clip(math.log(d_coarse / d_fine) / math.log(ratio), OBSERVED_RANGE[0], highest))


def asymptotic(d_fine: float, d_coarse: float, ratio: float) -> bool:
    """Whether two successive differences fall at least at the lowest order believed
    (:data:`OBSERVED_RANGE`): else the coarser companions are not yet converging, and their
    difference says nothing of the run's error."""
    return d_fine > 0 and d_coarse >= d_fine * ratio ** OBSERVED_RANGE[0]


def finer_companion(case, part: str, base: dict, against: str = "space") -> Companion:
    """The companion on the finer side of the run's setting (on the mesh ``base`` sets), for a
    part whose coarser companions are pre-asymptotic or out of range: half the step, or half as
    many harmonics again (at least one more), or a mesh twice as fine (a mesh section at an odd
    ``refine``, which cannot be coarsened)."""
    if part == "space":
        return Companion("space_up", {**base, "refine": 2 * case.refine}, against)
    if part == "time":
        return Companion("time_up", {**base, "dt": case.dt / 2}, against)
    return Companion("harmonics_up", {**base, "harmonics": max((3 * case.harmonics) // 2, case.harmonics + 1)},
                     against)


def estimate(case, solver: str, result, run=solve) -> dict:
    """``error_estimate`` of a run (``result`` of ``solver`` on ``case``): per probe the total and
    its parts (and each part's order), the companions' settings and CPU. ``run(solver, case)``
    makes a companion's result (the registry's ``solve`` by default).

    The estimate serves the run and never ends it: a companion that raises or does not converge
    leaves its part out (``partial``, with why under ``unmeasured``, the companion's message
    under ``failed``); where the coarse mesh fails, time and harmonics are measured on the run's
    own mesh instead. A third level that fails leaves its part at the assumed order."""
    planned = plan(case, solver)
    if not planned.companions and not planned.unmeasured:
        made_for = ", ".join(s.name for s in solvers() if s.estimated)
        return {"method": f"none: no estimate for {solver} (it is made for {made_for})"}
    results, cases, cpu, failed = {"run": result}, {"run": case}, {}, {}
    unmeasured, upward = dict(planned.unmeasured), dict(planned.upward)

    def made(c: Companion) -> bool:
        """Run companion ``c``; whether it finished (why not, in ``failed``)."""
        try:
            cases[c.name] = rebuild(case, c.overrides)
            outcome = run(solver, cases[c.name])
        except Exception as exc:  # noqa: BLE001 - the run is the user's: a companion costs only its part
            failed[c.name] = failure(exc)
            return False
        cpu[c.name] = float(outcome.cpu_time_s)
        if not outcome.converged:
            failed[c.name] = one_line(outcome.message or "did not converge")
            return False
        results[c.name] = outcome
        return True

    comps = planned.companions
    if comps and comps[0].name == "space" and not made(comps[0]):
        unmeasured["space"] = f"the space companion did not finish ({failed['space']})"
        rebased = plan(case, solver, on_coarse=False)  # time and harmonics on the run's own mesh
        comps, upward = rebased.companions, dict(rebased.upward)
        unmeasured.update(rebased.unmeasured)
    done = []
    for c in comps:
        if c.against in results and (c.name in results or made(c)):
            done.append(c)
        elif c.name in (c.part, upward.get(c.part)):  # the part's own companion: the part is lost
            unmeasured.setdefault(c.part, f"the {c.name} companion did not finish ({failed.get(c.name)})")
            upward.pop(c.part, None)
    by_name = {c.name: c for c in done}
    diffs = {c.name: _differences(case, results[c.against], results[c.name]) for c in done}
    fields = {p.name: p.field for p in case.probes}
    headline_probes = [n for n in result.history if fields.get(n) in ("u", "v")]
    probes = _parts(case, result, cases, by_name, diffs, upward)
    # a part whose coarser pair does not converge on a headline probe is measured on the finer
    # side, unless even its safe reading (the lowest order) hardly raises the run's estimate
    for part in (p for p in ("time", "harmonics") if f"{p}2" in by_name and p not in upward):
        ratio = _ratio(part, cases[part], cases[f"{part}2"])
        if not any(not asymptotic(diffs[part][n], diffs[f"{part}2"].get(n, math.nan), ratio)
                   for n in headline_probes if n in diffs[part]):
            continue
        rows = [probes[n] for n in headline_probes if n in probes]
        if rows and max(r["total"] for r in rows) <= (1 + NEGLIGIBLE) * max(r["total"] - r.get(part, 0.0) for r in rows):
            continue
        parent = by_name[part]
        base = {k: v for k, v in parent.overrides.items() if k not in ("dt", "harmonics")}
        c = finer_companion(case, part, base, parent.against)
        if not admissible(case, c.overrides):  # the safe reading stands
            failed[c.name] = "not run: its settings are outside the parameters' range"
            continue
        if not made(c):  # the safe reading stands
            continue
        by_name[c.name] = c
        done.append(c)
        diffs[c.name] = _differences(case, results[c.against], results[c.name])
        upward[part] = c.name
    if set(upward) - set(planned.upward):
        probes = _parts(case, result, cases, by_name, diffs, upward)
    out = {"method": "companions", "partial": bool(unmeasured)}
    if any(row["orders"] for row in probes.values()):
        out["probes"] = probes
    out |= {"companions": {c.name: c.overrides for c in done}, "measured_upward": sorted(upward),
            "companions_cpu_s": cpu, "companions_cpu_total_s": float(sum(cpu.values())),
            "run_cpu_s": float(result.cpu_time_s)}
    if unmeasured:
        out["unmeasured"] = unmeasured
    if failed:
        out["failed"] = failed
    return out


def _parts(case, result, cases: dict, by_name: dict, diffs: dict, upward: dict) -> dict:
    """Per probe the total and its parts with their orders; ``upward``: part -> the finer
    companion it is measured against."""
    probes = {}
    for name in result.history:
        row, orders = {}, {}
        for part in PARTS:
            measured = upward.get(part, part)
            if measured not in by_name or name not in diffs[measured]:
                continue
            c = by_name[measured]
            fine, coarse = cases[c.against], cases[measured]
            ratio = _ratio(part, fine, coarse)
            finer = ratio < 1  # the companion is on the finer side
            if part in upward:
                p = order(case, part)  # the finest pair: the scheme's order
            elif part == "space":
                p = space_order(case)
            elif f"{part}2" in by_name:
                p = observed_order(diffs[part][name], diffs[f"{part}2"].get(name, math.nan),
                                   _ratio(part, coarse, cases[f"{part}2"]), max(OBSERVED_RANGE[1], order(case, part)))
            else:
                p = order(case, part)
            d = diffs[measured].get(name, math.nan)
            # the run against a coarser companion: d / (r^p - 1); against a finer one: d / (1 - r^p)
            row[part] = d / (1.0 - ratio ** p) if finer else d / (ratio ** p - 1.0)
            orders[part] = p
        probes[name] = {"total": float(sum(row.values())), **{k: float(v) for k, v in row.items()},
                        "orders": orders}
    return probes


def headline(case, est: dict) -> tuple[str, float] | None:
    """The probe with the largest estimated total error over the displacement and velocity
    probes (the headline family), and that error; None without an estimate."""
    fields = {p.name: p.field for p in case.probes}
    rows = [(name, v["total"]) for name, v in est.get("probes", {}).items() if fields.get(name) in ("u", "v")]
    return max(rows, key=lambda r: r[1]) if rows else None


def summary_line(case, solver: str, est: dict) -> str:
    """One line for the end of ``smfem run``."""
    missing = "; ".join(f"{part}: {why}" for part, why in est.get("unmeasured", {}).items())
    if "probes" not in est:
        return f"{case.name} ({solver}): error estimate " + (f"none: no part measured ({missing})" if missing
                                                             else est["method"])
    top = headline(case, est)
    if not top:
        return f"{case.name} ({solver}): no displacement or velocity probe to estimate"
    parts = est["probes"][top[0]]
    split = ", ".join(f"{k} {100 * parts[k]:.2g} %" for k in PARTS if k in parts)
    partial = f"; partial, not measured: {missing}" if missing else ""
    claim = f"; no accuracy claimed: {est['claim'].removeprefix('none: ')}" if "claim" in est else ""
    return (f"{case.name} ({solver}): estimated error {100 * top[1]:.2g} % ({top[0]}: {split}){partial}; "
            f"companions {est['companions_cpu_total_s']:.3g} s CPU{claim}")
