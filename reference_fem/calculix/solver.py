"""``ccx`` on a case's deck, its results as a :class:`~cases.result.RunResult`.

Probes: ``'point'`` probes read the node at the probe point (the deck refuses a probe between
nodes); stresses and PEEQ are CalculiX's nodal values (extrapolated from its integration
points and averaged over the elements at the node). ``'max'`` of ``'peps'`` is the largest
nodal PEEQ. ``'body_mean'`` is mass-weighted with the reference mesh's consistent mass (the
serendipity field completed at the Lagrange face and centre nodes).

A scene with a rigid wall (the rod) is exported but not solved: ccx 2.20's implicit dynamics
has no wall contact that both converges and agrees (see :data:`WALL_REFUSED`).

CalculiX's PEEQ is the *accumulated* equivalent plastic strain; the cases' ``peps`` is
sqrt(2/3 eps_p : eps_p) of the current plastic strain. They agree while the plastic flow keeps
its direction; ``info['peps']`` says which one a run reports.
"""

from __future__ import annotations

import os
import re
import resource
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Callable

import numpy as np

from cases.params import ToolMissing, UnsupportedCase, newmark_only
from cases.result import RunResult

from ..frames import body_point_to_mesh, body_rotation
from ..probes import body_mean_row
from .deck import Deck, build_deck
from .procedures import EXPLICIT, IMPLICIT, MODAL, MODES, fixed_increments
from .frd import read_frd, read_sta
from .serendipity import once, shares

CCX = "ccx"
PEEQ_NOTE = ("PEEQ: CalculiX's accumulated equivalent plastic strain, nodal (extrapolated from the integration "
             "points), not the case's sqrt(2/3 eps_p:eps_p); equal while the flow keeps its direction")
#: the C3D20 mid-side nodes (in the VTK hexahedron's order 8 ... 19) and the faces' nodes


WALL_REFUSED = (
    "calculix: a rigid wall is not solved: in ccx 2.20's implicit dynamics its contact pairs cut the increment "
    "to nothing (energy-based impact control) and gap elements chatter against the face's consistent mass "
    "(the reference makes the contact nodes massless); smfem export writes the deck, with gap elements, all the same")


class CalculixMissing(ToolMissing):
    """``ccx`` is not on PATH (a clear one-line message, exit 2)."""


class CalculixFailed(RuntimeError):
    """``ccx`` ran but did not finish the step (its last message is in the text)."""


def find_ccx() -> str:
    """The ``ccx`` executable, or :class:`CalculixMissing`."""
    found = shutil.which(os.environ.get("SMFEM_CCX", CCX))
    if not found:
        raise CalculixMissing("calculix: ccx is not installed (Debian/Ubuntu: apt-get install calculix-ccx), "
                              "or set SMFEM_CCX to its path")
    return found


def solve(case, progress: Callable[[int, int], None] | None = None, workdir: Path | None = None,
          procedure: str = IMPLICIT, modes: int | None = None) -> RunResult:
    """Run ``case`` in CalculiX (the reference mesh, the case's window, one thread) by
    ``procedure`` (:mod:`.procedures`: ``implicit`` at the case's dt, ``explicit`` at ccx's
    Courant increment, ``modal`` with ``modes`` modes at the case's dt); what a procedure cannot
    take is refused in one line (:class:`UnsupportedCase`) before ccx runs.

    ``cpu_time_s`` is ccx's own CPU time (its model, factorizations and increments), as the
    other solvers count theirs; making the deck and reading the results are not in it.
    ``workdir`` keeps ccx's files there (else a temporary directory).
    """
    newmark_only(case, "calculix")
    if case.wall is not None and procedure == IMPLICIT:
        raise UnsupportedCase(WALL_REFUSED)
    deck = build_deck(case, procedure=procedure, modes=modes, fields=False)
    ccx = find_ccx()
    with tempfile.TemporaryDirectory(prefix="smfem-ccx-") as tmp:
        work = Path(workdir or tmp)
        work.mkdir(parents=True, exist_ok=True)
        (work / "job.inp").write_text(deck.text)
        cpu, log = run(ccx, work, case, progress)
        result = read_results(case, deck, work, log)
    result.cpu_time_s = cpu
    result.info["ccx"] = ccx
    return result


def read_results(case, deck: Deck, work: Path, log: str = "") -> RunResult:
    """The run in ``work`` (``job.frd``, ``job.sta``) as a :class:`RunResult` on the case's
    time grid (``cpu_time_s`` left 0)."""
    if not (work / "job.frd").exists():
        raise CalculixFailed(f"calculix: ccx wrote no results: {_last_error(log)}")
    blocks = read_frd(work / "job.frd", set(RESULTS.values()), _reducer(case, deck))
    increments = read_sta(work / "job.sta") if (work / "job.sta").exists() else []
    # the increments every result block has (a failed run's last one may be cut short)
    n_inc = min(len(b) for b in blocks.values()) if blocks else 0
    ccx_t = np.array([0.0] + [block[0] for block in next(iter(blocks.values()), [])[:n_inc]])
    fields_at = _Fields(deck, case, {name: [b[1:] for b in bs[:n_inc]] for name, bs in blocks.items()})
    ccx_history = {p.name: np.array([fields_at.initial(p)] + [fields_at.value(p, k) for k in range(n_inc)])
                   for p in case.probes}
    # onto the case's time grid (ccx's own increments, with plasticity, are not on it)
    grid = np.arange(case.n_steps + 1) * case.dt
    n_done = int(np.searchsorted(grid, ccx_t[-1] * (1 + 1e-9), side="right")) - 1
    t = grid[: n_done + 1]
    history = {k: np.interp(t, ccx_t, v) for k, v in ccx_history.items()}
    its = np.array([i for _, i in increments], int)
    ends = np.searchsorted(np.array([ti for ti, _ in increments]), t[1:] * (1 + 1e-9), side="right")
    iterations = np.diff(np.concatenate([[0], np.cumsum(its)[ends - 1] if its.size else np.zeros(n_done, int)]))
    converged = n_done == case.n_steps
    message = "" if converged else (f"calculix: stopped at t = {ccx_t[-1]:.6g} s, step {n_done} of {case.n_steps}: "
                                    f"{_last_error(log)}")
    eigen = [line.strip() for line in log.splitlines() if EIGEN_FAILED.search(line)]
    if eigen:  # ccx 2.20 goes on with zero modes, and writes zero histories as if all were well
        converged, message = False, (f"calculix (modal): ccx's eigensolver failed ({eigen[0]}): too many modes for "
                                     "this mesh; take fewer")
    info = {"procedure": deck.procedure, "element": deck.element, "n_elements": int(deck.elements.shape[0]),
            "dim": int(deck.points.shape[0]), "representation": deck.model.rep, "increments": len(increments),
            "time_step": "ccx's own, at most dt, interpolated onto the dt grid" if deck.procedure == IMPLICIT
            and not fixed_increments(case) else TIME_STEP[deck.procedure]}
    if deck.procedure == MODAL:
        info["modes"] = _modes(deck.text)
    if deck.procedure == EXPLICIT and ccx_t.size > 1:  # how far apart its outputs fell, in dt
        info.update(output_every=deck.every, output_spacing_dt=float(np.diff(ccx_t).max() / case.dt),
                    predicted_increment=deck.increment)
        selected = SELECTED_INCREMENT.search(log)
        if selected:
            info["ccx_increment"] = float(selected.group(1))
    if case.material.plastic:
        info["peps"] = PEEQ_NOTE
    return RunResult(t=t, history=history, n_dof=deck.nodes.size * deck.points.shape[0],
                     iterations=[int(i) for i in iterations], converged=bool(converged), message=message, info=info)


#: ccx's explicit increment in its output
SELECTED_INCREMENT = re.compile(r"SELECTED time increment:\s*(\S+)")
#: the .frd's result that holds each probe field
RESULTS = {"u": "DISP", "v": "VELO", "sigma": "STRESS", "peps": "PE"}


def _reducer(case, deck: Deck) -> Callable:
    """What to keep of each result block: the probes' nodes (every node where a probe takes a mean
    over the body) and the block's largest first component (a ``'max'`` probe's)."""
    kept = {}
    for probe in case.probes:
        name = RESULTS[probe.field]
        nodes = kept.setdefault(name, set())
        if probe.kind == "body_mean" or nodes is None:
            kept[name] = None
        elif probe.kind == "point":
            nodes.add(deck.probe_nodes[probe.name])
    kept = {name: None if nodes is None else np.array(sorted(nodes), int) for name, nodes in kept.items()}

    def reduce(name: str, nodes: np.ndarray, values: np.ndarray) -> tuple:
        peak = float(values[:, 0].max()) if values.size else 0.0
        wanted = kept.get(name, np.zeros(0, int))
        if wanted is not None:
            inside = np.isin(nodes, wanted)
            nodes, values = nodes[inside], values[inside]
        return nodes, values, peak

    return reduce


#: ccx's eigensolver (ARPACK's d[n,s]aupd / d[n,s]eupd) did not give the modes asked for
EIGEN_FAILED = re.compile(r"\*ERROR in d\[n,s\][ae]upd")
#: how each procedure steps, for ``info['time_step']`` (the plastic implicit runs' own increments aside)
TIME_STEP = {IMPLICIT: "dt", MODAL: "dt (each mode exact under piecewise-linear loads)",
             EXPLICIT: "ccx's own (Courant), written at least four times a dt and interpolated onto the dt grid"}


def _modes(text: str) -> int:
    """The mode count of a modal deck (the line after ``*FREQUENCY``)."""
    lines = text.splitlines()
    return int(lines[lines.index("*FREQUENCY, STORAGE=YES") + 1])


def run(ccx: str, work: Path, case, progress=None) -> tuple[float, str]:
    """Run ccx on ``work/job.inp`` with one thread; its CPU time and its output; ``progress(step,
    n_steps)`` from the step time of each increment ccx reports."""
    env = dict(os.environ, OMP_NUM_THREADS="1", CCX_NPROC_STIFFNESS="1", CCX_NPROC_EQUATION_SOLVER="1")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = []
    with subprocess.Popen([ccx, "-i", "job"], cwd=work, env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True) as proc:
        for line in proc.stdout:
            out.append(line)
            m = re.match(r"\s*actual (?:step )?time\s*=\s*(\S+)", line)
            if m and progress:
                progress(min(int(float(m.group(1)) / case.dt + 0.5), case.n_steps), case.n_steps)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, "".join(out)


def _last_error(log: str) -> str:
    errors = [line.strip() for line in log.splitlines() if "ERROR" in line]
    return errors[-1] if errors else (log.strip().splitlines() or ["no output"])[-1]


class _Fields:
    """The case's probes from ccx's nodal results, increment by increment."""

    def __init__(self, deck: Deck, case, blocks: dict):
        self.deck, self.case, self.blocks = deck, case, blocks
        self.dim = deck.points.shape[0]
        self.n_nodes = deck.points.shape[1]
        self._mass_rows = {}

    def nodal(self, name: str, k: int, width: int) -> np.ndarray:
        """Result ``name`` of increment ``k`` at every node of the reference mesh (0 where ccx has none)."""
        nodes, values, _ = self.blocks[name][k]
        out = np.zeros((self.n_nodes, width))
        inside = nodes <= self.n_nodes
        out[nodes[inside] - 1] = values[inside, :width]
        return out

    def initial(self, probe) -> float:
        if probe.field == "v" and probe.kind == "body_mean":
            v0 = self.deck.model.initial_velocity().reshape(-1, self.dim)
            return self._body_mean(probe, v0)
        if probe.field == "v":
            return self._rotate_vector(probe, self.deck.model.initial_velocity().reshape(-1, self.dim))
        return 0.0

    def value(self, probe, k: int) -> float:
        if probe.kind == "max" and probe.field == "peps":
            return max(self.blocks["PE"][k][2], 0.0)  # as over every node, those without PEEQ at 0
        if probe.kind == "point" and probe.field in ("u", "v"):
            return self._rotate_vector(probe, self.nodal("DISP" if probe.field == "u" else "VELO", k, 3))
        if probe.kind == "point" and probe.field == "peps":
            return float(self.nodal("PE", k, 1)[self.deck.probe_nodes[probe.name] - 1, 0])
        if probe.kind == "point" and probe.field == "sigma" and "n" not in probe.component:
            s = self.nodal("STRESS", k, 6)[self.deck.probe_nodes[probe.name] - 1]
            T = np.array([[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]])
            R = self._rotation(probe)
            i, j = (c - 1 for c in probe.component)
            return float((R @ T @ R.T)[i, j])
        if probe.kind == "body_mean" and probe.field in ("u", "v"):
            x = self.nodal("DISP" if probe.field == "u" else "VELO", k, 3)[:, : self.dim]
            return self._body_mean(probe, x)
        raise UnsupportedCase(f"calculix: probe {probe.name!r} ({probe.kind} of {probe.field}) is not available")

    def _rotation(self, probe) -> np.ndarray:
        x = body_point_to_mesh(self.case, self.deck.model.rep, probe.point)
        return body_rotation(self.case, self.deck.model.rep, x[:, None])[0]

    def _rotate_vector(self, probe, nodal: np.ndarray) -> float:
        u = np.zeros(3)
        u[: self.dim] = nodal[self.deck.probe_nodes[probe.name] - 1, : self.dim]
        return float((self._rotation(probe) @ u)[probe.component[0] - 1])

    def _body_mean(self, probe, nodal: np.ndarray) -> float:
        """Mass-weighted mean of a body component (consistent mass of the completed field)."""
        if probe.component not in self._mass_rows:
            self._mass_rows[probe.component] = body_mean_row(self.deck.model, probe.component[0])
        full = nodal[:, : self.dim].copy()
        if self.deck.serendipity:
            full = complete(self.deck.cells, full, self.dim)
        return float(self._mass_rows[probe.component] @ full.ravel())


def complete(cells: np.ndarray, nodal: np.ndarray, dim: int) -> np.ndarray:
    """``nodal`` values of a serendipity field (corner and mid-side nodes) with the Lagrange
    face and centre nodes of ``cells`` (VTK quad9 / hexahedron27) filled in: the serendipity
    interpolation there (-1/4 of the corners plus 1/2 of the mid-sides on a face or 2D centre;
    -1/4 of the corners plus 1/4 of the mid-sides at a hexahedron's centre)."""
    filled = np.zeros_like(nodal)
    for extra, nodes, weight in shares(cells, dim):
        extra, nodes = once(extra, nodes)
        filled[extra] += weight * nodal[nodes].sum(axis=1)
    extras = np.unique(cells[:, 8 if dim == 2 else 20:])
    nodal[extras] = filled[extras]
    return nodal
