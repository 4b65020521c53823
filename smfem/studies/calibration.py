"""Calibration of a truth: its distance to a second, independent truth path.

A stored truth is made twice: by its own path (:func:`smfem.studies.truth.plan_for`, ``full``)
and by a second one that shares as little as it can with it (the explicit reference against
the modal solution, the B-bar element against the standard one, implicit Newmark with
Lagrange-multiplier contact against central differences with a kinematic wall). For every
probe with a converged truth the distance between the two, in the error measure of the
report, is set against the two stated uncertainties:

- *covered*: the distance is at most the sum of the two uncertainties (each path's error is
  within its own bar, so the two paths are within the sum);
- *sharp*: the truth's own uncertainty is at most :data:`SHARPNESS` times the distance, where
  the distance is above :data:`FLOOR`. The floor is where sharpness stops mattering to the
  report: a truth judges a target only from :data:`~smfem.studies.metrics.TRUTH_MARGIN` times its
  uncertainty up, so an uncertainty of at most ``SHARPNESS * FLOOR`` judges the smallest
  target; below the floor two paths agree as well as the report can use.

Where a probe is not covered, the truth's stated uncertainty is widened to the distance plus the
second path's uncertainty (:func:`widen`): the smallest bar that covers the truth's error
if the second path's own bar is right. The truth's own estimate is kept beside it
(``own_uncertainty``) and a note says so: the two engines disagree by more than either
ladder sees, and which one is nearer the answer is not known, so the truth may not claim
its own, sharper bar. (ring_in_ring: its implicit path and the explicit one stay 0.10-0.18 %
apart on the inner ring's displacements at every mesh r1-r4 and time step dt / 32-dt / 64,
while each ladder moves by less than 0.08 %.)

Two paths that share a mesh ladder and an integrator (the B-bar and standard elements of the
notched scenes) share part of their error, so their distance is a lower bound of it; the
interleaved pair of the explicit method (:mod:`smfem.studies.truth`) measures the ladder's part.
"""

from __future__ import annotations

import math

import pandas as pd

from cases import get_case
from smfem.runs.errors import history_errors

from .metrics import TARGETS, TRUTH_MARGIN
from .plan import EXPLICIT, EXPLICIT_TRUTH, MODAL_TRUTH, REF2D, SMFEM_QUAD9, TIME_TRUTH, TruthPlan

#: the most a truth's stated uncertainty may exceed the distance to the second path
SHARPNESS = 3.0
#: distances below this (relative max-norm) are agreement: the sharpness rule is not applied
#: (module doc: 1 % / (3 x 3), about 0.11 %)
FLOOR = min(TARGETS) / (TRUTH_MARGIN * SHARPNESS)


def second_plan(name: str, main: TruthPlan) -> TruthPlan:
    """The second truth path of scene ``name`` whose main path is ``main``."""
    ladder = dict(refine=(2, 4, 8), check=(3, 6), output_divisor=main.output_divisor)
    case = get_case(name)
    if main.method == MODAL_TRUTH and case.section.kind == "mesh" and not case.axisymmetric:
        # the flywheel: its explicit or implicit reference is 3D only, past affordable; the other
        # code, SMFEM's 9-node element, by time-step halving (independent of the harmonic model's
        # numerics, though not of SMFEM's: a check of the truth, not the truth)
        return TruthPlan(TIME_TRUTH, refine=(1, 2), dt_divisors=(1, 2, 4), solver=SMFEM_QUAD9,
                         output_divisor=main.output_divisor)
    if main.method == MODAL_TRUTH:  # dome, thick cylinder: the explicit 2D reference
        return TruthPlan(EXPLICIT_TRUTH, solver=EXPLICIT, **ladder)
    if main.method == EXPLICIT_TRUTH and get_case(name).wall is not None:
        # the rod: implicit Newmark with exact (Lagrange multiplier) contact on a massless face
        return TruthPlan(TIME_TRUTH, refine=(4, 8), dt_divisors=(1, 2, 4, 8), solver=REF2D)
    if main.method == TIME_TRUTH:
        # ring_in_ring: central differences with impulse contact against implicit Newmark with
        # Lagrange multipliers, meshes r1-r2-r4 (an r8 would be hours in 2D)
        return TruthPlan(EXPLICIT_TRUTH, solver=EXPLICIT, refine=(1, 2, 4), output_divisor=main.output_divisor)
    if main.method == EXPLICIT_TRUTH:  # plastic scenes: the other element (B-bar or standard), same meshes
        options = dict(main.options)
        options["bbar"] = not options.get("bbar", False)
        return TruthPlan(EXPLICIT_TRUTH, solver=EXPLICIT, dim=main.dim, options=tuple(sorted(options.items())),
                         refine=main.refine, check=main.check, output_divisor=main.output_divisor)
    raise ValueError(f"no second truth path for a {main.method!r} truth")


def calibrate(case, truth, second) -> dict:
    """Per probe with a converged truth in both paths: ``distance``, ``uncertainty`` (the
    truth's), ``second_uncertainty``, ``covered`` and ``sharp``; and ``second_path``."""
    window = case.references.get("comparison_window_s", 0.0)
    out = {"second_path": second.name, "rule": f"covered: distance <= u + u2; sharp: u <= {SHARPNESS:g} "
                                              f"max(distance, {100 * FLOOR:.3g} %)", "probes": {}}
    for probe in case.probe_names:
        u, u2 = truth.uncertainty.get(probe, math.nan), second.uncertainty.get(probe, math.nan)
        if not (math.isfinite(u) and math.isfinite(u2)) or probe.startswith("peps"):
            continue
        distance = history_errors(second.t, second.values[probe], truth.t, truth.values[probe], window)[0]
        out["probes"][probe] = {
            "distance": distance, "uncertainty": u, "second_uncertainty": u2,
            "covered": bool(distance <= u + u2), "sharp": bool(u <= SHARPNESS * max(distance, FLOOR))}
    return out


def widen(truth, calibration: dict) -> list[str]:
    """Widen ``truth``'s uncertainty on every probe ``calibration`` (:func:`calibrate`) does not
    cover to ``distance + second_uncertainty``, recording ``own_uncertainty``, ``widened`` and
    the now ``covered`` and ``sharp`` verdicts in ``calibration``, and a note; the widened
    probes' names."""
    widened = []
    for probe, c in calibration["probes"].items():
        c["widened"] = not c["covered"]
        if c["covered"]:
            continue
        own, wide = c["uncertainty"], c["distance"] + c["second_uncertainty"]
        c.update(own_uncertainty=own, uncertainty=wide, covered=True,
                 sharp=bool(wide <= SHARPNESS * max(c["distance"], FLOOR)))
        truth.uncertainty[probe] = wide
        note = (f"uncertainty widened from its own {100 * own:.3g} % to the distance to the second path plus that "
                f"path's uncertainty ({100 * c['distance']:.3g} + {100 * c['second_uncertainty']:.3g} %)")
        truth.notes[probe] = f"{truth.notes[probe]}; {note}" if truth.notes.get(probe) else note
        widened.append(probe)
    return widened


def table(truths: dict) -> pd.DataFrame:
    """One row per case and probe of every truth (``name -> Truth``) with a calibration."""
    rows = []
    for name, truth in truths.items():
        cal = truth.calibration or {}
        for probe, c in cal.get("probes", {}).items():
            rows.append({"case": name, "probe": probe, "truth": truth.name, "second_path": cal["second_path"],
                         "uncertainty_pct": 100 * c["uncertainty"],
                         "second_uncertainty_pct": 100 * c["second_uncertainty"],
                         "distance_pct": 100 * c["distance"], "covered": c["covered"], "sharp": c["sharp"],
                         "widened": c.get("widened", False)})
    return pd.DataFrame(rows)
