"""The reference each error is measured against, and the published and theoretical curves.

Order of preference for the error reference of a case (the tables name the one used):
an analytic history where it is exact for the case as set up, then a published history, then
the finest reference-FEM run. No case has a published *history*: the dome's published data
are three extrema read off a curve (two significant digits), compared in a table of their own
(:func:`published_points`) rather than used as the 1 % yardstick.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

ANALYTIC, REFERENCE_FEM = "analytic", "reference FEM"


@dataclass
class HistoryReference:
    """Probe histories to measure errors against. ``values[probe]`` is sampled at ``t``."""

    kind: str
    name: str
    t: np.ndarray
    values: dict


@dataclass
class PublishedPoints:
    """Published extrema of one probe: ``points`` ``[(t, value)]``, ``kinds`` min/max."""

    probe: str
    source: str
    points: list
    kinds: list


def rod_histories(theory: dict, t: np.ndarray) -> dict:
    """The 1-D rod theory of :func:`cases.rod_impact.rod_theory` as probe histories.

    The rod moves at -v0 towards the wall; while in contact the struck face rests and a stress
    wave -rho c v0 runs up and back; after 2 L / c the rod leaves at +v0, stress free. The mean
    velocity changes linearly in between (constant contact force).
    """
    (t0, t1), (m0, m1) = theory["t_contact"], theory["t_mid_stress"]
    v0, s = theory["rebound_velocity"], theory["stress"]
    contact = (t >= t0) & (t < t1)
    return {
        "mid_szz": np.where((t >= m0) & (t < m1), s, 0.0),
        "contact_p": np.where(contact, s, 0.0),
        "end_uz": np.where(t < t0, -v0 * t, np.where(t < t1, -v0 * t0, -v0 * t0 + v0 * (t - t1))),
        "rod_vz": -v0 + 2 * v0 * np.clip((t - t0) / (t1 - t0), 0.0, 1.0),
    }


def theory_curves(case) -> HistoryReference | None:
    """A theory's histories over the case's window (for the figures), if the case has one."""
    theory = case.references.get("rod_theory")
    if theory is None:
        return None
    t = np.linspace(0.0, case.t_end, 20 * case.n_steps + 1)
    exact = case.material.nu == 0 and not case.material.plastic
    name = "1-D rod theory" + (" (exact for nu = 0)" if exact else f" (nu = {case.material.nu:g}: not exact)")
    return HistoryReference(ANALYTIC if exact else "theory", name, t, rod_histories(theory, t))


def best_history(case, reference_run) -> HistoryReference | None:
    """The error reference of ``case``: an exact analytic history, else the finest
    reference-FEM run (:class:`smfem.studies.cache.Run`), else None."""
    theory = theory_curves(case)
    if theory is not None and theory.kind == ANALYTIC:
        return theory
    if reference_run is None or not reference_run.usable:
        return None
    h = reference_run.history
    name = f"{reference_run.job.solver} {reference_run.label} (finest reference FEM)"
    if reference_run.status != "ok":  # a run that stopped early still compares over its window
        name += f", {reference_run.status} after t = {h['t'].iloc[-1]:.3g} s"
    return HistoryReference(REFERENCE_FEM, name, h["t"].to_numpy(), {c: h[c].to_numpy() for c in h.columns[1:]})


def published_points(case) -> list[PublishedPoints]:
    """Published extrema (``references['<probe>_extrema']``) of the case's probes."""
    out = []
    for probe in case.probe_names:
        ref = case.references.get(f"{probe}_extrema")
        if ref is not None:
            out.append(PublishedPoints(probe, ref["source"], list(ref["points"]), list(ref["kinds"])))
    return out
