"""The case's loads as deck cards: pressures (``*DLOAD``) and force terms (``*CLOAD``), each
under an ``*AMPLITUDE`` that carries its history in time.

* A pressure held from t = 0 is under ``STEPLOAD`` (as every pressure was before loads varied).
* A pressure with an amplitude is under its own table (:meth:`Amplitudes.name`).
* A pressure moving along x3 loads each facet of its surface with the fraction of the facet
  it covers at time t (:func:`moving_pressure`): piecewise linear in t, so an exact table,
  one per x3 layer of facets. A uniform pressure times that fraction is not the nodal force
  of a partly covered facet (the reference integrates the covered part, :mod:`..moving`), so
  CalculiX differs from the reference at the patch's edges by a facet-size effect.
* A force term (body force or traction) is the reference's assembled vector moved onto the
  serendipity nodes (:func:`serendipity_forces`) as ``*CLOAD`` lines; its ``time`` must be
  ``"1"`` (its amplitude, if any, a table).
"""

from __future__ import annotations

import math

import numpy as np

from cases.geometry import RING
from cases.params import UnsupportedCase

from ..frames import AXISYMMETRIC
from .serendipity import once, shares

#: numbers per *AMPLITUDE data line (four (t, factor) pairs; ccx reads up to eight numbers)
AMPLITUDE_PER_LINE = 8
#: an axisymmetric (CAX8) *CLOAD is the force on the whole circumference, the reference's is per
#: radian (measured: the dome under a body force agrees with the reference to 0.04 % so, and is
#: 1/180 of it with the force of a 2 degree segment, the convention of the wall's gap springs)
CAX_CIRCUMFERENCE = 2 * math.pi
#: relative round-off under which two amplitude tables are the same and a breakpoint is a repeat
SAME = 1e-12
#: a covered fraction this close to 0 or 1 is that (round-off where a patch end meets a facet end)
SNAP = 1e-9


class Amplitudes:
    """The deck's ``*AMPLITUDE`` tables, each once under its first name (the facets of one x3
    layer of a moving load share one). Every table runs from t = 0 to at least ``t_end``: one
    that starts later or ends earlier is continued as a constant: the *AMPLITUDE convention
    (ccx 2.20 gave the same histories for a ramp with and without its held last point), made
    explicit so that the deck does not lean on it."""

    def __init__(self, t_end: float):
        self.t_end = t_end
        self.names: dict[tuple, str] = {}  # a table's key -> its name
        self.points: dict[str, list] = {}  # name -> its (t, factor) points

    def name(self, points, name: str) -> str:
        """The name of the table through ``points`` ``((t, factor), ...)``: ``name``, or the
        one an identical table was given before."""
        points = [(float(t), float(f)) for t, f in points]
        if points[0][0] > 0.0:
            points.insert(0, (0.0, points[0][1]))
        if points[-1][0] < self.t_end:
            points.append((self.t_end, points[-1][1]))
        key = tuple((round(t / (SAME * self.t_end)), round(f / SAME)) for t, f in points)
        if key not in self.names:
            self.names[key] = name
            self.points[name] = points
        return self.names[key]

    def cards(self) -> list[str]:
        lines = []
        for name, points in self.points.items():
            values = [f"{v:.13g}" for point in points for v in point]
            lines += [f"*AMPLITUDE, NAME={name}",
                      *(", ".join(values[i : i + AMPLITUDE_PER_LINE]) for i in range(0, len(values), AMPLITUDE_PER_LINE))]
        return lines


def refuse_early(case) -> None:
    """What the loads' cards cannot carry, refused before the model is built (the one check:
    :func:`pressure_cards`, :func:`moving_pressure` and :func:`force_cards` take it as made)."""
    for load in case.loads:
        _refuse_pressure(load)
    for term in case.forces:
        _refuse_force(term)


def _refuse_pressure(load) -> None:
    if load.mode is not None:
        raise UnsupportedCase("calculix: a single-harmonic load (mode) is not exported")
    if load.moving and load.amplitude is not None:
        raise UnsupportedCase("calculix: a moving pressure with an amplitude is not exported (its facets' "
                              "histories are not piecewise linear)")


def _refuse_force(term) -> None:
    if term.time != "1":
        raise UnsupportedCase(f"calculix: a force whose time is the expression {term.time!r} is not exported "
                              "(only an amplitude table: time = 1)")


def pressure_cards(case, model, faces, amplitudes: Amplitudes) -> list[str]:
    """``*DLOAD`` face loads of the case's pressures; ``faces(facets)`` gives the deck's
    ``(element, face number)`` of boundary facets."""
    lines = []
    for i, load in enumerate(case.loads, 1):
        if load.moving:
            lines += [f"** load {i} moves at {load.speed:.13g} per s along x3: each facet under the fraction of it "
                      f"covered (LOAD{i}_<j>)"]
            for name, facets in moving_pressure(model, load, amplitudes, f"LOAD{i}"):
                lines += [f"*DLOAD, AMPLITUDE={name}", *(f"{e + 1}, P{k}, {load.q:.13g}" for e, k in faces(facets))]
            continue
        name = "STEPLOAD" if load.amplitude is None else amplitudes.name(load.amplitude.points, f"LOAD{i}")
        lines += [f"*DLOAD, AMPLITUDE={name}"]
        lines += [f"{e + 1}, P{k}, {load.q:.13g}" for e, k in faces(model.load_facets(load))]
    return lines


def moving_pressure(model, load, amplitudes: Amplitudes, prefix: str) -> list[tuple[str, np.ndarray]]:
    """A moving pressure as ``(amplitude name, facets)`` groups: each facet of its surface
    under the fraction of it covered at time t, one table per x3 layer of facets (facets never
    covered before t_end are left out).

    The fraction is linear in t between the times a patch end passes a facet end (x3 is affine
    along each facet, :class:`~reference_fem.moving.MovingPressure` checks it), so a table
    through those times, 0 and t_end, is exact; the fraction at them is the reference's own
    (``MovingPressure.coverage``: a prism's clipping, a ring's wrap-around)."""
    from ..moving import MovingPressure

    try:
        unit = MovingPressure(model, load)
    except UnsupportedCase as err:
        raise UnsupportedCase("calculix: " + str(err).removeprefix("reference solver: ")) from None
    t_end = amplitudes.t_end
    # each facet's x3 range, rounded, names its layer
    ends = np.sort(np.column_stack([unit.z0, unit.z0 + unit.dz]), axis=1)
    scale = max(np.abs(ends).max(), 1.0)
    _, first, layer_of = np.unique(np.round(ends / (SAME * scale)), axis=0, return_index=True, return_inverse=True)
    layer_of = layer_of.ravel()
    times = [_layer_times(ends[f], load, model.case.body == RING, t_end) for f in first]
    grid = np.unique(np.concatenate(times))
    covered = np.array([np.subtract(*unit.coverage(t)[::-1])[first] for t in grid])  # (n_times, n_layers)
    covered = np.clip(covered, 0.0, 1.0)
    covered[covered < SNAP], covered[covered > 1.0 - SNAP] = 0.0, 1.0  # round-off of a facet's end
    groups = []
    for j, t in enumerate(times):
        fraction = covered[np.searchsorted(grid, t), j]
        if fraction.max() <= SAME:
            continue
        name = amplitudes.name(zip(t, fraction), f"{prefix}_{len(groups) + 1}")
        groups.append((name, unit.facets[layer_of == j]))
    return groups


def _layer_times(ends, load, ring: bool, t_end: float) -> np.ndarray:
    """0, t_end and the times in between at which an end of one of ``load``'s intervals passes
    an end of the x3 range ``ends`` (on a ring: modulo 2 pi, every turn), repeats merged."""
    period = 2 * math.pi / abs(load.speed) if ring else math.inf
    out = [0.0, t_end]
    for edge in (e for interval in load.x3_intervals for e in interval):
        for x in ends:
            t0 = (x - edge) / load.speed
            if ring:
                out += list(t0 + period * np.arange(math.ceil(-t0 / period), math.floor((t_end - t0) / period) + 1))
            else:
                out.append(t0)
    t = np.unique([min(max(v, 0.0), t_end) for v in out])
    return t[np.concatenate([[True], np.diff(t) > SAME * t_end])]


def force_cards(case, model, amplitudes: Amplitudes, to_deck) -> list[str]:
    """``*CLOAD`` nodal forces of the case's force terms (body forces, tractions): the
    reference's assembled vector of each term moved onto the deck's nodes by ``to_deck``
    (``(n_nodes, dim) -> (n_nodes, dim)``: :func:`serendipity_forces`, or none for a deck on
    every node), under its amplitude (``STEPLOAD`` without one); a supported dof's force is
    left out (a reaction there)."""
    lines = []
    fixed = np.zeros(model.basis.N, bool)
    fixed[model.fixed] = True
    for i, term in enumerate(case.forces, 1):
        _, F = model.force_vector(term)
        F = np.where(fixed, 0.0, F).reshape(-1, model.dim)
        F = to_deck(F) * (CAX_CIRCUMFERENCE if model.rep == AXISYMMETRIC else 1.0)
        name = "STEPLOAD" if term.amplitude is None else amplitudes.name(term.amplitude.points, f"FORCE{i}")
        node, comp = np.nonzero(np.abs(F) > SAME * np.abs(F).max())
        if node.size:  # a force on supported dofs only is all reaction
            lines += [f"*CLOAD, AMPLITUDE={name}", *(f"{n + 1}, {c + 1}, {F[n, c]:.13g}" for n, c in zip(node, comp))]
    return lines


def serendipity_forces(F: np.ndarray, cells: np.ndarray, dim: int) -> np.ndarray:
    """Nodal forces ``F`` ``(n_nodes, dim)`` of the Lagrange mesh (quad9 / hexahedron27, VTK
    order) as the consistent forces of its serendipity elements: each face or centre node's
    force shared among the corners and mid-sides by the serendipity shape functions' values
    there (the transpose of :func:`.solver.complete`), zero left at those nodes."""
    out = F.copy()
    for extra, nodes, weight in shares(cells, dim):
        extra, nodes = once(extra, nodes)  # each node's force goes out once
        np.add.at(out, nodes, weight * F[extra][:, None, :])
    out[np.unique(cells[:, 8 if dim == 2 else 20 :])] = 0.0
    return out
