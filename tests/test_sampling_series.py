"""The stress points' synthesis and projection along x3 through two series per section dof
(:class:`smfem.sampling.DofSeries`) against their definition, mode by mode: stresses, forces
and a plastic run's histories."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from cases import get_case
from cases.geometry import Cutout
from smfem import fourier
from smfem.assembly import element_dofs
from smfem.elements import DOFS_PER_NODE
from smfem.model import Model
from smfem.sampling import SamplePoints
from smfem.solver import solve


def dense_stress(model, points: SamplePoints, u: np.ndarray) -> np.ndarray:
    """``f D sum_m psi_m(x3) B_m u_m`` at every sample point, mode by mode: (6, ne, ng, nq)."""
    D, dofs = model.element_D(spread=1), element_dofs(model.mesh.elements)
    out = np.zeros(points.point_shape)
    for s, lo, hi in zip(model.systems, model.offsets[:-1], model.offsets[1:]):
        B = model.ops.at_samples(fourier.wavenumber(s.mode, model.body, model.length))  # (ne, ng, 6, d)
        stress = (D @ (B @ (s.T @ u[lo:hi])[dofs][:, None, :, None]))[..., 0]  # (ne, ng, 6)
        psi = np.array(fourier.psi(s.mode, points.x3, model.body, model.length))[fourier.ROW_TYPE]  # (6, nq)
        out += np.einsum("egr,rq->regq", stress, psi)
    return out * points.factor[None, :, None, :]


def dense_forces(model, points: SamplePoints, sigma: np.ndarray) -> np.ndarray:
    """``sum_q w_q sum_g B_m' psi_m(x3_q) sigma`` per mode, stacked."""
    dofs, forces = element_dofs(model.mesh.elements), []
    for s in model.systems:
        B = model.ops.at_samples(fourier.wavenumber(s.mode, model.body, model.length)) * model.ops.sample_weights[:, :, None, None]
        psi = np.array(fourier.psi(s.mode, points.x3, model.body, model.length))[fourier.ROW_TYPE] * points.w
        full = np.zeros(DOFS_PER_NODE * model.mesh.n_nodes)
        np.add.at(full, dofs, np.einsum("egrd,regq,rq->ed", B, sigma, psi))
        forces.append(s.T.T @ full)
    return np.concatenate(forces)


def turned_cylinder(harmonics: int):
    """The notched cylinder's cut-out turned by 30 degrees: both ring families."""
    case = get_case("notched_cylinder", {"harmonics": harmonics})
    c = case.cutouts[0]
    return dataclasses.replace(case, cutouts=(Cutout(c.s_range, c.t_range, tuple(
        (a + math.pi / 6, b + math.pi / 6) for a, b in c.x3_intervals)),))


@pytest.mark.parametrize("case, families", [
    (get_case("moving_load_notched", {"harmonics": 30}), {"p"}),  # no symmetry along x3
    (get_case("notched_strip", {"harmonics": 30}), {"p"}),  # odd harmonics over half the span
    (get_case("notched_cylinder", {"harmonics": 12}), {"c"}),
    (turned_cylinder(8), {"c", "s"})], ids=["prism", "prism-mirrored", "ring-c", "ring-c-s"])
def test_series_stresses_and_forces_are_the_products_mode_by_mode(case, families):
    """Stresses of random amplitudes and forces of random stresses (all points, and only some
    points along x3, as the relaxed stresses of a plastic step are) equal the definition to
    round-off, for the prism's modes and both ring families."""
    model = Model(case, nonlinear=True)
    assert {m.family for m in model.modes} == families
    points = SamplePoints(model, oversampling=1.0)
    rng = np.random.default_rng(7)
    u = rng.normal(size=model.n_dof)
    expected = dense_stress(model, points, u)
    assert np.abs(points.stress(u) - expected).max() <= 1e-12 * np.abs(expected).max()
    sigma = rng.normal(size=points.point_shape)
    sigma[..., rng.random(points.point_shape[-1]) < 0.8] = 0.0  # yielded along a fifth of x3
    for stresses in (sigma, expected):
        f = dense_forces(model, points, stresses)
        assert np.abs(points.forces(stresses) - f).max() <= 1e-12 * np.abs(f).max()
    # stresses at a few scattered points only, as a step's plastic increments are (2 %), and at
    # many (30 %: the whole arrays' path)
    for share in (50, 3):
        at = np.sort(rng.choice(sigma[0].size, size=max(3, sigma[0].size // share), replace=False))
        values = rng.normal(size=(6, len(at)))
        f = dense_forces(model, points, scattered(points, values, at))
        assert np.abs(points.forces_at(values, at) - f).max() <= 1e-12 * np.abs(f).max()


@pytest.mark.parametrize("name, params, mirrored", [
    ("moving_load_notched", {"harmonics": 60}, True),  # the notch centred: points about mid-span
    ("notched_cylinder", {"harmonics": 12}, True),  # about the middle of the quarter
    ("notched_strip", {"harmonics": 30}, False)])  # the notch at one end of the half span
def test_the_series_by_parity_about_the_middle_are_the_whole_products(name, params, mirrored):
    """Where the points along x3 and their weights are symmetric about their middle and every
    mode even or odd there, the series made at half the points by parity equal the whole
    product to round-off; elsewhere there is no parity to take."""
    from smfem.sampling import MirrorParity

    model = Model(get_case(name, params), nonlinear=True)
    points = SamplePoints(model, oversampling=1.0)
    series = points.series
    parity = MirrorParity.of(series.psi, points.x3, points.w)
    assert (parity is not None) == mirrored
    if mirrored:
        c = series.coefficients(np.random.default_rng(2).normal(size=model.n_dof))
        whole = np.concatenate([c[:, rows].T @ series.psi[t] for t, rows in enumerate(series.types)])
        assert np.abs(parity.values(c, series.types, len(whole)) - whole).max() <= 1e-13 * np.abs(whole).max()


def scattered(points: SamplePoints, values: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Stresses ``values`` (6, k) at the flat points ``at``, zero elsewhere: (6, ne, ng, nq)."""
    full = np.zeros((6, int(np.prod(points.point_shape[1:]))))
    full[:, at] = values
    return full.reshape(points.point_shape)


class DensePoints(SamplePoints):
    """Stress points whose synthesis and projection are the products mode by mode."""

    def stress(self, u):
        return dense_stress(self.model, self, u)

    def stress_at(self, u, points, coefficients=None):
        return dense_stress(self.model, self, u).reshape(6, -1)[:, points]

    def forces(self, sigma):
        return dense_forces(self.model, self, sigma)

    def forces_at(self, values, at):
        return dense_forces(self.model, self, scattered(self, values, at))


def test_a_plastic_run_through_the_series_has_the_histories_of_the_products_mode_by_mode(monkeypatch):
    """The notched strip into its plastic hinge (plastic from step 14 of 31, the notch's probe from
    step 22): the same iterations and histories within 1e-9 of each probe's largest value."""
    case = get_case("notched_strip", {"harmonics": 40, "t_end": 1.0e-4})
    series = solve(case, with_fields=False)
    monkeypatch.setattr("smfem.iterative.SamplePoints", DensePoints)
    dense = solve(case, with_fields=False)
    assert series.iterations == dense.iterations
    assert np.abs(dense.history["peps_notch"]).max() > 0
    for name, h in dense.history.items():
        assert np.abs(series.history[name] - h).max() <= 1e-9 * np.abs(h).max(), name
