"""Synthesis along x3 and projection back, per call of the plastic iterations (issue 57).

    python benchmarks/x3_sampling.py [--tiny] [--scenes NAME ...] [--harmonics H ...] [--repeat N] [--runs H ...]

For each scene and harmonic count: the stress points (stress rows, the series' rows, points
along x3 by today's rule, ``cases/x3_points.csv``) and the time of one ``stress`` plus one
``forces`` (CPU milliseconds, best of ``--repeat`` rounds of five calls each, one thread):

* ``rows``: the dense products over six stress rows per section sample point, ``D B u`` of
  every mode first (the path before :class:`smfem.sampling.DofSeries`, rebuilt here);
* ``series``: :class:`smfem.sampling.SamplePoints` as it is (dense products over two series per
  carried dof);
* ``finufft``: the same series by nonuniform FFTs at the same points (FINUFFT, type 2 for the
  synthesis, type 1 for the projection, tolerance 1e-13, two real rows packed into one complex
  transform; ``-`` where finufft is not installed);
* ``uniform``: the series by DST/DCT on ``H + 1`` uniform points, or the next size FFTs like
  (``uniform points``): the midpoint rule, exact for the modes' products over a prism's whole
  length, the rule a body without cut-out edges could use (the notched scenes cannot: this is
  what such a body would pay, not these scenes); ``uniform, dense``: the same points by the
  series' dense products (fewer points alone).

Each fast variant is checked against the dense products (1e-10 of the largest value). Then
whole runs of the notched moving load at ``--runs`` harmonics: their CPU and the share of it
inside ``stress`` and ``forces`` (issue 57: at most 10 % at 480 harmonics).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.fft
import scipy.sparse as sp

from cases import get_case, x3_points
from smfem.assembly import element_dofs
from smfem.elements import DOFS_PER_NODE
from smfem.model import Model
from smfem.sampling import DofSeries, SamplePoints, carried_dofs
from smfem.solver import solve

SCENES = ("moving_load_notched", "notched_strip")
HARMONICS = (60, 120, 240, 480)
#: the phase ``z`` with ``psi_type(l x) = Re(z exp(i l x))``, per family and basis type
PHASE = {"c": (1.0, -1j), "s": (-1j, -1.0), "p": (-1j, 1.0)}


class RowProducts:
    """Stresses and forces by dense products over the six stress rows of every sample point."""

    def __init__(self, model, points: SamplePoints):
        B = np.stack([model.ops.at_samples(k) for k in points.series.k])  # (modes, ne, ng, 6, d)
        n_modes, ne, ng, _, d = B.shape
        self.DB = (model.element_D(spread=1) @ B).reshape(n_modes * ne, ng * 6, d)
        self.Bt = (B * model.ops.sample_weights[None, :, :, None, None]).reshape(n_modes * ne, ng * 6, d)
        self.Bt = self.Bt.transpose(0, 2, 1).copy()
        dofs = element_dofs(model.mesh.elements)
        scatter = sp.csr_matrix((np.ones(dofs.size), (dofs.ravel(), np.arange(dofs.size))),
                                shape=(DOFS_PER_NODE * model.mesh.n_nodes, dofs.size))
        self.G = sp.block_diag([s.T.T @ scatter for s in model.systems], format="csr")
        self.Gt = self.G.T.tocsr()
        self.psi, self.psi_w, self.shape = points.series.psi, points.series.psi_w, (n_modes, ne, ng)
        # every element's factor (the stress rows' path scales them all)
        self.scale, self.rows = points.factor[None, :, None, :], (slice(0, 4), slice(4, 6))  # psi1, psi3 rows

    def stress(self, u):
        n_modes, ne, ng = self.shape
        a = (self.DB @ (self.Gt @ u).reshape(n_modes * ne, -1, 1)).reshape(n_modes, ne * ng, 6).transpose(2, 1, 0)
        out = np.empty((6, ne * ng, self.psi.shape[2]))
        for t, rows in enumerate(self.rows):
            out[rows] = a[rows] @ self.psi[t]
        return out.reshape(6, ne, ng, -1) * self.scale

    def forces(self, sigma):
        n_modes, ne, ng = self.shape
        projected = np.empty((6, ne * ng, n_modes))
        for t, rows in enumerate(self.rows):
            projected[rows] = sigma.reshape(6, ne * ng, -1)[rows] @ self.psi_w[t]
        return self.G @ (self.Bt @ projected.transpose(2, 1, 0).reshape(n_modes * ne, ng * 6, 1)).ravel()


class NonuniformSeries:
    """:meth:`DofSeries.values` and ``project`` by FINUFFT at the series' own points: a row's
    series is ``Re sum_l D_l exp(i l theta)`` (``theta = x3`` on a ring, ``pi x3 / length`` on a
    prism), two real rows one complex transform."""

    def __init__(self, model, points: SamplePoints):
        import finufft

        self.series, self.w = points.series, points.w
        self.l = np.array([s.mode.l for s in model.systems])
        self.phase = np.array([PHASE[s.mode.family] for s in model.systems]).T  # (2, modes)
        self.middle = int(self.l.max()) + 1  # frequencies -middle ... middle - 1
        theta = points.x3 if model.body == "ring" else points.x3 * np.pi / model.length
        self.plans = []
        for rows in self.series.types:
            pairs = -(-(rows.stop - rows.start) // 2)
            synthesis = finufft.Plan(2, (2 * self.middle,), n_trans=pairs, eps=1e-13, isign=1, nthreads=1)
            projection = finufft.Plan(1, (2 * self.middle,), n_trans=pairs, eps=1e-13, isign=1, nthreads=1)
            synthesis.setpts(theta), projection.setpts(theta)
            self.plans.append((synthesis, projection))

    @staticmethod
    def _pairs(rows: np.ndarray) -> np.ndarray:
        """Rows ``a, b`` as one complex row ``a + i b``, a zero row to pad."""
        if len(rows) % 2:
            rows = np.vstack([rows, np.zeros((1, rows.shape[1]), rows.dtype)])
        return rows[0::2] + 1j * rows[1::2]

    @staticmethod
    def _unpaired(packed: np.ndarray, count: int) -> np.ndarray:
        """The rows ``a, b`` of complex rows ``a + i b`` of two real results."""
        return np.stack([packed.real, packed.imag], axis=1).reshape(-1, packed.shape[1])[:count]

    def values(self, u):
        s, middle = self.series, self.middle
        coefficients = s.coefficients(u).T  # (2 n, modes)
        positive = np.unique(self.l[self.l > 0])
        out = np.empty((2 * s.n_dof, len(self.w)))
        for t, rows in enumerate(s.types):
            D = np.zeros((rows.stop - rows.start, 2 * middle), complex)  # the row is Re sum_l D_l e^{i l x}
            np.add.at(D.T, middle + self.l, (coefficients[rows] * self.phase[t]).T)
            hermitian = 0.5 * D  # the same real row as sum over -l ... l
            hermitian[:, middle] = D[:, middle].real
            hermitian[:, middle - positive] = 0.5 * np.conj(D[:, middle + positive])
            out[rows] = self._unpaired(self.plans[t][0].execute(self._pairs(hermitian)), rows.stop - rows.start)
        return out

    def project(self, duals):
        s, middle = self.series, self.middle
        projected = np.empty((2 * s.n_dof, s.n_modes))
        for t, rows in enumerate(s.types):
            g = self.plans[t][1].execute(self._pairs(duals[rows] * self.w))  # sum_q (a + i b) e^{i l x}
            at, mirror = g[:, middle + self.l], np.conj(g[:, middle - self.l])  # of a: (at + mirror) / 2
            both = np.stack([0.5 * (at + mirror), -0.5j * (at - mirror)], axis=1).reshape(-1, len(self.l))
            projected[rows] = (self.phase[t] * both[:rows.stop - rows.start]).real
        return s.amplitudes(projected)


class UniformSeries:
    """The series' products on ``H + 1`` or a few more uniform points of a prism (midpoints of equal cells
    over the length) by DST/DCT: psi1 ``sin(l pi x / L)`` by types III (synthesis) and II
    (projection), psi3 ``cos`` likewise; a prism's modes are ``l = 1 ... H``."""

    def __init__(self, model):
        if model.body != "prism":
            raise ValueError("the uniform grid here is a prism's")
        self.l = np.array([s.mode.l for s in model.systems])
        self.n = scipy.fft.next_fast_len(int(self.l.max()) + 1, real=True)  # H + 1 or the next size FFTs like
        self.weight = model.length / self.n
        x3 = (np.arange(self.n) + 0.5) * self.weight
        self.series = DofSeries(model, carried_dofs(model), x3, np.full(self.n, self.weight))

    def values(self, u):
        s = self.series
        coefficients = s.coefficients(u).T
        out = np.empty((2 * s.n_dof, self.n))
        for t, rows in enumerate(s.types):
            grid = np.zeros((rows.stop - rows.start, self.n))
            if t == 0:  # DST-III: x_k at frequency k + 1, halved (none at the last, l = n)
                grid[:, self.l - 1] = 0.5 * coefficients[rows]
                out[rows] = scipy.fft.dst(grid, type=3, axis=1, workers=1)
            else:  # DCT-III: x_k at frequency k, halved but x_0 (l = 0, absent)
                grid[:, self.l] = 0.5 * coefficients[rows]
                out[rows] = scipy.fft.dct(grid, type=3, axis=1, workers=1)
        return out

    def project(self, duals):
        s = self.series
        projected = np.empty((2 * s.n_dof, s.n_modes))
        for t, rows in enumerate(s.types):
            if t == 0:
                projected[rows] = scipy.fft.dst(duals[rows], type=2, axis=1, workers=1)[:, self.l - 1]
            else:
                projected[rows] = scipy.fft.dct(duals[rows], type=2, axis=1, workers=1)[:, self.l]
        return s.amplitudes(0.5 * self.weight * projected)


def per_call(calls, repeat: int) -> float:
    """CPU milliseconds per round of ``calls`` (best of ``repeat`` rounds of 5)."""
    best = np.inf
    for _ in range(repeat):
        t0 = time.process_time()
        for _ in range(5):
            for call in calls:
                call()
        best = min(best, (time.process_time() - t0) / 5)
    return 1e3 * best


def off(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / np.abs(b).max())


def measure(name: str, harmonics: int, repeat: int) -> dict:
    case = get_case(name, {"harmonics": harmonics})
    model = Model(case, nonlinear=True)
    points = SamplePoints(model, x3_points.oversampling(case.name, harmonics)[0])
    u = np.random.default_rng(0).normal(size=model.n_dof)
    rows = RowProducts(model, points)
    sigma = rows.stress(u)
    flat, forces = sigma.reshape(-1, len(points.x3)), rows.forces(sigma)
    assert off(points.stress(u), sigma) < 1e-10 and off(points.forces(sigma), forces) < 1e-10
    out = {"scene": name, "H": harmonics, "modes": len(model.systems), "stress rows": flat.shape[0],
           "series rows": 2 * points.series.n_dof, "points": len(points.x3),
           "rows": per_call((lambda: rows.stress(u), lambda: rows.forces(sigma)), repeat),
           "series": per_call((lambda: points.stress(u), lambda: points.forces(sigma)), repeat)}
    try:
        nonuniform = NonuniformSeries(model, points)
    except ImportError:
        out["finufft"] = None
    else:
        factor = points.factor[None, :, None, :]
        stress = lambda: (points.to_stress @ nonuniform.values(u)).reshape(points.point_shape) * factor
        project = lambda: nonuniform.project(points.from_stress @ flat)
        assert off(stress(), sigma) < 1e-10 and off(project(), forces) < 1e-10
        out["finufft"] = per_call((stress, project), repeat)
    if model.body == "prism":
        uniform = UniformSeries(model)
        exact = uniform.series.values(u)
        assert off(uniform.values(u), exact) < 1e-10
        assert off(uniform.project(exact), uniform.series.project(exact)) < 1e-10
        out["uniform points"] = uniform.n
        out["uniform"] = per_call((lambda: points.to_stress @ uniform.values(u),
                                   lambda: uniform.project(points.from_stress @ (points.to_stress @ exact))), repeat)
        out["uniform, dense"] = per_call((lambda: points.to_stress @ uniform.series.values(u),
                                          lambda: uniform.series.project(points.from_stress @ (points.to_stress @ exact))),
                                         repeat)
    return out


def run_share(harmonics: int, sets: dict) -> str:
    """A moving_load_notched run's CPU and the share of it inside ``SamplePoints.stress`` and
    ``.forces`` (process time)."""
    spent = {"stress": 0.0, "forces": 0.0}
    originals = {name: getattr(SamplePoints, name) for name in spent}

    def timed(name, method):
        def wrapper(self, *args):
            t0 = time.process_time()
            try:
                return method(self, *args)
            finally:
                spent[name] += time.process_time() - t0
        return wrapper

    for name, method in originals.items():
        setattr(SamplePoints, name, timed(name, method))
    try:
        t0 = time.process_time()
        solve(get_case("moving_load_notched", {"harmonics": harmonics, **sets}), with_fields=False)
        total = time.process_time() - t0
    finally:
        for name, method in originals.items():
            setattr(SamplePoints, name, method)
    return (f"moving_load_notched run, {harmonics} harmonics: CPU {total:.2f} s, stress {spent['stress']:.2f} s, "
            f"forces {spent['forces']:.2f} s: x3 sampling {100 * sum(spent.values()) / total:.1f} % of the run")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tiny", action="store_true", help="one small size (the tests run every benchmark so)")
    ap.add_argument("--scenes", nargs="+", default=SCENES)
    ap.add_argument("--harmonics", nargs="+", type=int, default=HARMONICS)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--runs", nargs="*", type=int, default=(240, 480), help="harmonics of whole runs to measure")
    args = ap.parse_args(argv)
    scenes, counts, repeat = (SCENES[-1:], (20,), 1) if args.tiny else (args.scenes, args.harmonics, args.repeat)
    columns = ("scene", "H", "modes", "stress rows", "series rows", "points", "rows", "series", "finufft",
               "uniform points", "uniform", "uniform, dense")
    print(" | ".join(columns))
    for name in scenes:
        for harmonics in counts:
            row = measure(name, harmonics, repeat)
            print(" | ".join("-" if row.get(c) is None else f"{row[c]:.2f}" if isinstance(row[c], float) else str(row[c])
                             for c in columns), flush=True)
    for harmonics in (20,) if args.tiny else args.runs:
        print(run_share(harmonics, {"t_end": 5 * get_case("moving_load_notched").dt} if args.tiny else {}), flush=True)


if __name__ == "__main__":
    from smfem.runs import threads

    threads.pin()  # one BLAS thread, as in smfem's own entry points
    main()
