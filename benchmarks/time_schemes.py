"""Does a better time treatment move SMFEM's work-precision front? (elastic thick cylinder, dome)

    python benchmarks/time_schemes.py [--cases thick_cylinder dome] [--divisors 1 2 4 8 16 32 64]
                                      [--gauss-divisors 1 2 4 8 16] [--repeat 2] [--tiny]

Per scene and spatial level (SMFEM's front levels, moment4, and the quadratic element's, quad9)
at dt = the case's dt over each divisor: the total error against the stored truth (the quick
report's headline measure: the largest relative max-norm error over the displacement and
velocity probes, ``smfem.runs.errors.history_errors``) and the CPU time (best of ``--repeat``, one
BLAS thread) of

plain        SMFEM as it is: Newmark average acceleration, the trapezoidal rule (smfem.runs.registry);
richardson   the plain runs at dt and dt/2 combined at dt's steps, u_dt/2 + (u_dt/2 - u_dt) / 3;
             CPU: both runs;
bathe        Bathe's composite scheme (a trapezoidal half step, then the three-point backward
             Euler), its two solves per step; its error exact, at the modal level (below); its
             CPU counted as the plain run at dt/2 (as many solves): a lower bound, Bathe also
             factorizes a second matrix;
gauss        the 2-stage Gauss-Legendre method: order 4, A-stable, no numerical damping (for a
             linear system the (2,2) Pade approximant of the exponential): a time loop on
             SMFEM's own matrices, one complex solve with K - c M, c = 6 (-1 + i sqrt 3) / dt^2,
             and one product with K per step;
exact        no time error at all: per harmonic, the eigenmodes of SMFEM's (K, M) (dense), the
             step response superposed in closed form at the truth's output times (every dt / 16).
             CPU: model, eigensolutions and the output.

The modal level: per harmonic, ``M^(-1/2) K M^(-1/2)`` decomposed densely, so that a scheme's
step is a scalar recurrence per mode; Newmark's, run so, reproduces SMFEM's run to round-off (the
``modal check`` line). Against ``exact`` each run's time error alone is measured too, with its
observed order between halvings (the trapezoidal rule's is 2 only once the step resolves the
modes the step load excites; Richardson's premise). Then, per scheme, over the moment4 levels and
over all, the CPU time to reach 1 % and 5 % along the front (smfem.studies.metrics: ``pareto_front``,
``cost_to``).

Elastic scenes homogeneous along x3 with a held load and no initial velocity only (the modal
level and the Gauss loop take the load as constant; both scenes' step loads are).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from cases import get_case
from reports.analysis import family_of
from smfem.runs import threads
from smfem.runs.errors import history_errors
from smfem.runs.registry import SMFEM, solve
from smfem.model import Model
from smfem.probes import ProbeSet
from smfem.stacking import stacked
from smfem.studies import metrics
from smfem.studies.plan import quick, select
from smfem.studies.stored import directory, read
from smfem.studies.study import stored_truth

#: spatial levels per scene: SMFEM's front in the quick report (moment4), then quad9's
LEVELS = {
    "thick_cylinder": ({"harmonics": 20}, {"refine": 2, "harmonics": 40}, {"refine": 4, "harmonics": 80},
                       {"element": "quad9", "harmonics": 20}, {"element": "quad9", "harmonics": 40},
                       {"element": "quad9", "harmonics": 80},
                       {"element": "quad9", "refine": 2, "harmonics": 80}),
    "dome": ({"refine": 1}, {"refine": 2}, {"refine": 4}, {"element": "quad9"},
             {"element": "quad9", "refine": 2}),
}
SCHEMES = ("plain", "richardson", "bathe", "gauss", "exact")


def label(level: dict) -> str:
    """``r4 H80``, ``q9 r2 H80``, ``r1`` (an axisymmetric scene has no harmonics)."""
    text = f"r{level.get('refine', 1)}" + (f" H{level['harmonics']}" if "harmonics" in level else "")
    return ("q9 " if level.get("element") == "quad9" else "") + text


def error(case, probes, t, history, t_ref, reference) -> float:
    """The headline measure over ``probes``: the largest relative max-norm error of ``history``
    (probe -> values at ``t``) against ``reference`` (at ``t_ref``)."""
    window = case.references.get("comparison_window_s", 0.0)
    return max(history_errors(t, history[p], t_ref, reference[p], window)[0] for p in probes)


def best_of(repeat: int, run):
    """``run()``'s result with the least CPU time of ``repeat`` calls (``result[-1]``: CPU s)."""
    return min((run() for _ in range(repeat)), key=lambda result: result[-1])


def plain(case):
    result = solve(SMFEM, case)
    return result.t, result.history, result.cpu_time_s


def richardson(coarse, fine):
    """The plain runs at dt and dt/2 combined at dt's steps (their two CPU times summed)."""
    t, a, cpu_a = coarse
    _, b, cpu_b = fine
    return t, {p: b[p][::2] + (b[p][::2] - a[p]) / 3 for p in a}, cpu_a + cpu_b


def newmark_step(u, v, a, w2, h):
    """One step of the trapezoidal rule (average acceleration) on free modes ``u'' = -w2 u``."""
    a0 = 4.0 / (h * h)
    predicted = u + h * v + (0.25 * h * h) * a
    u_new = a0 * predicted / (w2 + a0)
    a_new = a0 * (u_new - predicted)
    return u_new, v + 0.5 * h * (a + a_new), a_new


def bathe_step(u, v, a, w2, h):
    """One step of Bathe's composite scheme: the trapezoidal rule over h / 2, then the
    three-point backward Euler over the whole step."""
    um, vm, _ = newmark_step(u, v, a, w2, 0.5 * h)
    u_new = ((4.0 * vm - v) / h - 3.0 * (u - 4.0 * um) / (h * h)) / (9.0 / (h * h) + w2)
    v_new = (u - 4.0 * um + 3.0 * u_new) / h
    return u_new, v_new, (v - 4.0 * vm + 3.0 * v_new) / h


def linear_parts(case, model: Model):
    """The parts of an elastic SMFEM model the prototypes below take: ``K``, the mass diagonal
    ``M``, the held load ``Q`` and the probe operator; refuses what they do not handle."""
    K, M, Q, V0, _ = stacked(model)
    if model.coupling or case.forces or np.any(V0) or M.ndim != 1:
        raise ValueError(f"{case.name}: the prototypes take decoupled harmonics, a held load and no initial "
                         "velocity only")
    return K, M, Q, ProbeSet(model, case.probes)


class Modes:
    """The step response of an elastic SMFEM model, mode by mode.

    Per harmonic block ``M^(-1/2) K M^(-1/2) = Y diag(omega^2) Y'``; the response is
    ``static - W cos(omega t)`` exactly, with ``W`` (n_probes, n_modes) the probes of each
    mode's share of the static solution. Zero-frequency modes (rigid motions no load drives)
    get no share.
    """

    def __init__(self, case):
        cpu0 = time.process_time()
        model = Model(case)
        _, _, _, probes = linear_parts(case, model)
        if probes.on_v is not None:
            raise ValueError(f"{case.name}: the modal level gives displacement probes only")
        P = probes.on_u.toarray()
        self.names = probes.names
        shares, omegas = [], []
        for block, system in enumerate(model.systems):
            root_m = np.sqrt(system.M)
            lam, Y = la.eigh((system.K.toarray() / root_m[:, None]) / root_m[None, :])
            force = Y.T @ (system.Q / root_m)
            moving = lam > 1e3 * np.finfo(float).eps * lam.max()  # below: round-off of a zero frequency
            static = np.where(moving, force / np.where(moving, lam, 1.0), 0.0)
            on_probes = P[:, model.offsets[block]:model.offsets[block + 1]] / root_m[None, :]
            shares.append((on_probes @ Y) * static[None, :])
            omegas.append(np.sqrt(np.maximum(lam, 0.0)))
        self.W, self.omega = np.hstack(shares), np.concatenate(omegas)
        self.static = self.W.sum(axis=1)
        self.cpu = time.process_time() - cpu0

    def exact(self, t: np.ndarray) -> dict:
        """Probe -> values at times ``t`` (s), with no time error."""
        values = self.static[:, None] - self.W @ np.cos(self.omega[:, None] * t[None, :])
        return dict(zip(self.names, values))

    def march(self, step, h: float, n: int) -> tuple[np.ndarray, dict]:
        """Times and probe histories of ``n`` steps of ``step`` (as :func:`newmark_step`) from
        rest under the held load: each mode's deviation from its static share, from -1."""
        w2 = self.omega ** 2
        u, v, a = -np.ones_like(w2), np.zeros_like(w2), w2.copy()  # a = -w2 u: the load on at t = 0
        rows = [u]
        for _ in range(n):
            u, v, a = step(u, v, a, w2, h)
            rows.append(u)
        values = self.static[:, None] + self.W @ np.array(rows).T
        return np.arange(n + 1) * h, dict(zip(self.names, values))


def gauss(case):
    """The 2-stage Gauss-Legendre method on SMFEM's matrices: ``(u, v)`` from
    ``D y_new = N y + h b``, with ``N, D = I +- h A / 2 + h^2 A^2 / 12`` of ``y' = A y + b``.
    Eliminating ``v``: ``(M + h^2 K / 12 + h^4 K M^-1 K / 144) u_new = rhs``, whose matrix is
    ``(h^4 / 144) (K - c M) M^-1 (K - conj(c) M)``: one complex solve per step gives ``u_new``
    (the imaginary part, scaled) and ``K u_new`` (from ``K z = rhs + c M z``)."""
    cpu0 = time.process_time()
    K, M, Q, probes = linear_parts(case, Model(case))
    h = case.dt
    c = 6.0 * (-1.0 + 1j * math.sqrt(3.0)) / (h * h)
    lu = sla.splu((K - c * sp.diags(M)).astype(complex).tocsc())
    scale = 144.0 / h**4 / c.imag
    u = v = Ku = np.zeros(K.shape[0])
    rows = [probes.evaluate(u, v)]
    for _ in range(case.n_steps):
        p = Ku / M
        rhs = M * (u + h * v) - (5 * h * h / 12) * Ku + K @ ((h**4 / 144) * p - (h**3 / 12) * v) + (h * h / 2) * Q
        z = lu.solve(rhs)
        u_new, Ku_new = scale * z.imag, scale * M * (c * z).imag
        v = (2 / h) * (u_new - (h * h / 12) * Ku_new / M - (u + 0.5 * h * v - (h * h / 12) * p))
        u, Ku = u_new, Ku_new
        rows.append(probes.evaluate(u, v))
    cpu = time.process_time() - cpu0
    return np.arange(case.n_steps + 1) * h, dict(zip(probes.names, np.array(rows).T)), cpu


def local_orders(errors: list) -> str:
    """log2 of the ratio of each error to the next (halved step): the observed orders."""
    pairs = zip(errors, errors[1:])
    return " ".join(f"{math.log2(a / b):.2f}" if a > 0 and b > 0 and math.isfinite(a / b) else "-" for a, b in pairs)


def measure_level(name: str, level: dict, base: dict, truth, args) -> list[dict]:
    """Every scheme's points at one spatial level (printed by :func:`show_level`)."""
    case = get_case(name, {**base, **level})
    probes = [p.name for p in case.probes if family_of(p) == "headline" and truth.converged(p.name)]
    modes = Modes(case)
    grid = truth.t[truth.t <= case.t_end * (1 + 1e-12)]  # the truth's output times
    cpu0 = time.process_time()
    exact = modes.exact(grid)
    exact_cpu = modes.cpu + time.process_time() - cpu0

    def at(divisor):
        return get_case(name, {**base, **level, "dt": case.dt / divisor})

    def point(scheme, divisor, run):
        t, history, cpu = run
        return {"scheme": scheme, "level": label(level), "element": level.get("element", "moment4"),
                "divisor": divisor, "dt": case.dt / divisor if divisor else math.nan, "cpu": cpu,
                "total": error(case, probes, t, history, truth.t, truth.values),
                "time": error(case, probes, t, history, grid, exact)}

    runs = {d: best_of(args.repeat, lambda d=d: plain(at(d))) for d in args.divisors}
    halved = [d for d in args.divisors if 2 * d in runs]
    points = [point("plain", d, runs[d]) for d in args.divisors]
    points += [point("richardson", d, richardson(runs[d], runs[2 * d])) for d in halved]
    points += [point("bathe", d, (*modes.march(bathe_step, case.dt / d, d * case.n_steps), runs[2 * d][2]))
               for d in halved]
    points += [point("gauss", d, best_of(args.repeat, lambda d=d: gauss(at(d)))) for d in args.gauss_divisors]
    points.append({**point("exact", 0, (grid, exact, exact_cpu)), "time": 0.0})
    t, history, _ = runs[args.divisors[0]]
    check = error(case, probes, t, history, *modes.march(newmark_step, t[1] - t[0], len(t) - 1))
    print(f"\n{name} {label(level)}: {len(modes.omega)} dof, exact in time {100 * points[-1]['total']:.3f} % "
          f"at {exact_cpu:.3f} s CPU; modal check (Newmark on the modes against SMFEM's run) {check:.1e}")
    show_level(points)
    return points


def show_level(points: list[dict]) -> None:
    """Per divisor, each time-stepping scheme's total error and CPU time, and its time error
    alone; then the observed orders."""
    steppers = SCHEMES[:4]
    print("  dt/d   " + "".join(f"{s:>24s}" for s in steppers) + "      time error alone (%)")
    print("         " + "".join(f"{'total %':>14s}{'CPU s':>10s}" for _ in steppers)
          + "   " + "  ".join(steppers))
    by = {(p["scheme"], p["divisor"]): p for p in points}
    for d in sorted({p["divisor"] for p in points if p["divisor"]}):
        cells, times = "", ""
        for scheme in steppers:
            p = by.get((scheme, d))
            cells += f"{100 * p['total']:14.3f}{p['cpu']:10.3f}" if p else f"{'':24s}"
            times += f"{100 * p['time']:9.4f}" if p else f"{'':9s}"
        print(f"  {d:4d} {cells}  {times}")
    for scheme in steppers:
        mine = sorted((p for p in points if p["scheme"] == scheme), key=lambda p: p["divisor"])
        dt, total, alone = ([p[k] for p in mine] for k in ("dt", "total", "time"))
        print(f"  {scheme:>10s} orders between halvings: total {local_orders(total)}; time alone "
              f"{local_orders(alone)}; least squares over the ladder: total {metrics.observed_order(dt, total):.2f}, "
              f"time {metrics.observed_order(dt, alone):.2f}")


def fronts(points: list[dict], uncertainty: float) -> None:
    """Per scheme, over the moment4 levels and over all: the front and the CPU to each target."""
    print(f"\n  CPU s to reach {' and '.join(f'{100 * t:g} %' for t in metrics.TARGETS)} along each front "
          "(the label of the cheapest run there); front")
    for scheme in SCHEMES:
        for which in ("moment4", "all"):
            mine = [p for p in points if p["scheme"] == scheme and (which == "all" or p["element"] == "moment4")]
            cpu, total = [p["cpu"] for p in mine], [p["total"] for p in mine]
            labels = [f"{p['level']}" + (f" dt/{p['divisor']}" if p["divisor"] else "") for p in mine]
            costs = [metrics.cost_to(t, cpu, total, labels, uncertainty).text() for t in metrics.TARGETS]
            front = ", ".join(f"{labels[i]} {100 * total[i]:.2f} % {cpu[i]:.3f} s"
                              for i in metrics.pareto_front(cpu, total))
            print(f"  {scheme:>10s} {which:>7s}: " + "   ".join(f"{c:28s}" for c in costs) + f"  [{front}]")


def main(argv=None):
    threads.pin()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=list(LEVELS), choices=list(LEVELS))
    ap.add_argument("--divisors", type=int, nargs="+", default=[1, 2, 4, 8, 16, 32, 64])
    ap.add_argument("--gauss-divisors", type=int, nargs="+", default=[1, 2, 4, 8, 16])
    ap.add_argument("--repeat", type=int, default=2, help="CPU time: the best of this many runs")
    ap.add_argument("--tiny", action="store_true", help="a few steps of the smallest settings (the tests run every benchmark so)")
    args = ap.parse_args(argv)
    if args.tiny:
        args.cases, args.divisors, args.gauss_divisors, args.repeat = ["thick_cylinder"], [1, 2, 4], [1, 2], 1
    for name in args.cases:
        levels, base = LEVELS[name], {}
        if args.tiny:  # a quarter of the window, 8 harmonics: the truth's history covers it
            levels = ({"harmonics": 8}, {"element": "quad9", "harmonics": 8})
            base = {"t_end": get_case(name).t_end / 4}
            truth = read(directory(name))
        else:
            truth, why = stored_truth(select(quick(), [name])[0])
            if truth is None:
                raise SystemExit(f"{name}: {why}")
        headline = [p.name for p in get_case(name).probes if family_of(p) == "headline"]
        print(f"{name}: total error against {truth.source} (uncertainty {100 * truth.uncertainty_of(headline):.2f} %)")
        points = [p for level in levels for p in measure_level(name, level, base, truth, args)]
        fronts(points, truth.uncertainty_of(headline))


if __name__ == "__main__":
    main()
