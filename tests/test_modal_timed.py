"""The modal truth under loads that vary in time: amplitudes integrated exactly, a moving patch
sampled with a measured error, checked against integrations built here by other means."""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import pytest
import scipy.linalg as la

from cases import get_case
from cases.geometry import PRISM, Amplitude, Force, interval_fourier
from cases.params import UnsupportedCase
from reference_fem import modal
from reference_fem.harmonic import HarmonicModel, unsupported_reason


def _pulse_model(**sets) -> HarmonicModel:
    """The layered cylinder under the pulse: harmonics 0 and 2 (82 amplitudes at most)."""
    return HarmonicModel(get_case("layered_cylinder", {"load": "pulse", "harmonics": 3, **sets}))


def _relative(mine: dict, exact: dict) -> float:
    return max(np.abs(mine[p] - exact[p]).max() / np.abs(exact[p]).max() for p in exact)


# -- an independent integration: the matrix exponential of the first-order system -------------
def _propagator(h, Q: np.ndarray, step: float):
    """``expm`` over ``step`` of ``M a + K u = Q (phi + sigma s)`` as a first-order system in
    ``[q, p, phi, sigma]``: ``q = L' u`` (``M = L L'``), ``p = q' / s`` with ``s`` the largest
    frequency (no block dwarfs another), and ``phi' = sigma`` making the force linear in time.
    Returns the propagator, ``L`` and ``s``."""
    L = la.cholesky(h.M.toarray(), lower=True)
    A = la.solve_triangular(L, la.solve_triangular(L, h.K.toarray(), lower=True).T, lower=True)
    n = A.shape[0]
    s = np.sqrt(np.abs(la.eigvalsh(A)).max())
    G = np.zeros((2 * n + 2, 2 * n + 2))
    G[:n, n:2 * n] = s * np.eye(n)
    G[n:2 * n, :n] = -A / s
    G[n:2 * n, 2 * n] = la.solve_triangular(L, Q, lower=True) / s
    G[2 * n, 2 * n + 1] = 1.0
    return la.expm(G * step), L, s


def _expm_histories(model, tau: np.ndarray, t: np.ndarray) -> dict:
    """Probe histories at ``t`` (among ``tau``) of every harmonic's single timed load, its factor
    linear between the samples ``tau``, stepped piece by piece with the matrix exponential."""
    out = np.zeros((len(model.probes), t.size))
    is_v = np.array([f == "v" for f in model.fields])
    at = {float(v): k for k, v in enumerate(t)}
    for h in model.systems:
        (term,) = h.terms
        n = h.K.shape[0]
        f = term.factor(tau)
        propagators = {}
        x = np.zeros(2 * n + 2)
        for j, step in enumerate(np.diff(tau)):
            if step not in propagators:
                propagators[step] = _propagator(h, term.Q, step)
            E, L, s = propagators[step]
            x[2 * n], x[2 * n + 1] = f[j], (f[j + 1] - f[j]) / step
            x = E @ x
            k = at.get(float(tau[j + 1]))
            if k is not None:
                u, v = la.solve_triangular(L.T, x[:n]), la.solve_triangular(L.T, s * x[n:2 * n])
                out[:, k] += np.where(is_v, h.P @ v, h.P @ u)
    return dict(zip(model.probes, out))


def _only(model, h):
    """``model`` with the single harmonic ``h`` (a shallow copy)."""
    one = copy.copy(model)
    one.systems = [h]
    return one


def test_pulse_is_exact_against_the_matrix_exponential():
    """The pulse's piecewise-linear amplitude is integrated exactly: the modal histories equal
    a step-by-step matrix exponential of the harmonics' own matrices to 1e-8."""
    model = _pulse_model(t_end=1.2e-3)
    case = model.case
    t = np.arange(case.n_steps + 1) * case.dt
    tau = np.union1d(t, case.loads[0].amplitude.times)  # its kinks (output times here too) and the outputs
    assert _relative(modal.histories(model, t).history, _expm_histories(model, tau, t)) < 1e-8


def test_sampled_moving_load_is_integrated_exactly_between_its_samples():
    """The moving patch's factor, linear between the modal solver's own samples (pieces cut
    into equal sub-steps), against the matrix exponential on those samples: the same to 1e-8,
    so what remains is the sampling alone (measured below)."""
    case = get_case("moving_load", {"harmonics": 3, "t_end": 1e-4, "dt": 1e-5})
    model = HarmonicModel(case)
    t = np.arange(case.n_steps + 1) * case.dt
    for h in model.systems:
        s = modal.timeline(h.terms[0], t)
        assert s.steps.min() > 1  # each output interval cut into sub-steps
        m = modal.modes_of(h)
        y, _ = modal.modal_coordinates(m.omega, s.tau, h.terms[0].factor(s.tau), s.out, s.steps)
        mine = dict(zip(model.probes, m.terms[0].coef @ y))
        assert _relative(mine, _expm_histories(_only(model, h), s.tau, t)) < 1e-8


def test_one_mode_is_the_sum_of_its_ramp_responses():
    """``y'' + w^2 y = f``, ``f`` through (0, 0), (2, 1), (6, 0) and zero after: the superposed
    responses to its ramps, ``(s - sin(w s) / w) / w^2`` and ``(1 - cos w s) / w^2`` (a rigid
    mode: ``s^3 / 6`` and ``s^2 / 2``), for slow to fast modes, one step per interval or four."""
    omega = np.array([0.0, 0.3, 1.7, 40.0, 1e4])
    t = np.arange(11.0)
    slopes = ((0.0, 0.5), (2.0, -0.75), (6.0, 0.25))
    s = [np.maximum(t - at, 0.0) for at, _ in slopes]
    for w, y, yd in zip(omega, *(modal.modal_coordinates(omega, t, np.interp(t, (0, 2, 6), (0, 1, 0)),
                                                         np.arange(11)))):
        ramp = [x**3 / 6 if w == 0 else (x - np.sin(w * x) / w) / w**2 for x in s]
        rate = [x**2 / 2 if w == 0 else (1 - np.cos(w * x)) / w**2 for x in s]
        exact_y, exact_v = (sum(k * r for (_, k), r in zip(slopes, rr)) for rr in (ramp, rate))
        # round-off of phases up to w t = 1e5 rad: ~1e-11
        assert np.abs(y - exact_y).max() < 1e-10 * np.abs(exact_y).max(), w
        assert np.abs(yd - exact_v).max() < 1e-10 * np.abs(exact_v).max(), w
    tau = np.linspace(0.0, 10.0, 41)
    cut = modal.modal_coordinates(omega, tau, np.interp(tau, (0, 2, 6), (0, 1, 0)), np.arange(0, 41, 4), np.full(10, 4))
    whole = modal.modal_coordinates(omega, t, np.interp(t, (0, 2, 6), (0, 1, 0)), np.arange(11))
    np.testing.assert_allclose(cut[0], whole[0], rtol=0, atol=1e-12 * np.abs(whole[0]).max())


def test_moving_factor_is_the_interval_integral_at_each_time():
    """The array form of the moving patch's share equals ``interval_fourier`` over
    ``intervals_at`` at every time, entering, crossing and leaving the span."""
    case = get_case("moving_load")
    load = case.loads[0]
    times = np.linspace(0.0, case.t_end, 997)
    for l in (1, 2, 7, 60):
        scalar = [interval_fourier(load.intervals_at(t, PRISM, case.length), l, "sin", PRISM, case.length)
                  for t in times]
        np.testing.assert_allclose(interval_fourier(load.ends_at(times, PRISM, case.length), l, "sin", PRISM, case.length), scalar,
                                   rtol=0, atol=1e-15)


# -- the step and the amplitudes ----------------------------------------------------------------
def test_held_step_is_the_closed_form():
    """A held step keeps its closed form: every harmonic's ``(1 - cos w t) / w^2`` response,
    built here from a dense eigendecomposition, to round-off; no timed term is made."""
    case = get_case("layered_cylinder", {"harmonics": 3, "t_end": 1e-3})
    model = HarmonicModel(case)
    t = np.arange(case.n_steps + 1) * case.dt
    exact = 0.0
    for h in model.systems:
        assert not h.terms
        w2, phi = la.eigh(h.K.toarray(), h.M.toarray())
        exact = exact + ((h.P @ phi) * (phi.T @ h.Q) / w2) @ (1 - np.cos(np.outer(np.sqrt(w2), t)))
    assert _relative(modal.histories(model, t).history, dict(zip(model.probes, exact))) < 1e-12


def test_amplitude_held_at_one_is_the_step():
    """An amplitude at 1 from its first point, (0, 1), (1, 1), is the step: the same histories
    by the piecewise-linear path as by the closed form."""
    step = get_case("layered_cylinder", {"harmonics": 3, "t_end": 1e-3})
    held = dataclasses.replace(step, loads=tuple(dataclasses.replace(x, amplitude=Amplitude(((0.0, 1.0), (1.0, 1.0))))
                                                 for x in step.loads))
    t = np.arange(step.n_steps + 1) * step.dt
    a, b = HarmonicModel(step), HarmonicModel(held)
    assert all(h.terms and not np.any(h.Q) for h in b.systems)
    assert _relative(modal.histories(b, t).history, modal.histories(a, t).history) < 1e-11


def test_newmark_converges_to_the_modal_pulse_at_second_order():
    """Newmark on the same matrices with the pulse's ``Q(t)`` at each step: its error against the
    modal histories falls by 4 per halving of dt, so the modal answer is its dt -> 0 limit (once
    dt resolves the highest mode the pulse's kinks excite: a coarse mesh keeps that quick)."""
    model = _pulse_model(t_end=8e-4, coarsen=4)
    case = model.case
    divisors = (64, 128, 256)
    t = np.arange(20 * divisors[-1] + 1) * case.dt / divisors[-1]
    exact = modal.histories(model, t).history
    errors = []
    for d in divisors:
        newmark = modal.newmark_histories(model, case.dt / d, 20 * d)
        errors.append(max(np.abs(newmark[p] - exact[p][:: divisors[-1] // d]).max() / np.abs(exact[p]).max()
                          for p in model.probes))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((orders > 1.9) & (orders < 2.1)), (orders, errors)


def test_mode_acceleration_with_a_timed_load():
    """A truncated basis under the pulse: the modes left out answering statically (``static f``)
    bring the displacement within 1e-3 of the whole basis, ten times closer than without."""
    model = _pulse_model(t_end=2e-3)
    t = np.arange(model.case.n_steps + 1) * model.case.dt
    for h in model.systems:
        whole, cut = modal.modes_of(h), modal.modes_of(h, n_modes=20)
        assert cut.terms[0].static is not None and cut.omega.size == 20
        u = modal.term_response(whole, whole.terms[0], modal.term_coordinates(whole.omega, h.terms[0], t))[0]
        coordinates = modal.term_coordinates(cut.omega, h.terms[0], t)
        gap = np.abs(modal.term_response(cut, cut.terms[0], coordinates)[0] - u).max() / np.abs(u).max()
        without = np.abs(cut.terms[0].coef @ coordinates.y - u).max() / np.abs(u).max()
        assert gap < 1e-3 and gap < without / 10, (h.l, gap, without)


# -- the moving load's sampling -----------------------------------------------------------------
def test_moving_load_sampling_is_measured_and_small():
    """The moving patch's sampling error is reported per probe, below 1e-5, and it bounds what
    twice the samples change: about a quarter of it, the measure being the change from half the
    samples (second order: three times the error it leaves)."""
    case = get_case("moving_load", {"harmonics": 12})
    result = modal.solve(case)
    stated = result.info["load_sampling"]
    assert set(stated) == set(case.probe_names)
    assert all(0 < v < 1e-5 for v in stated.values()), stated
    model = HarmonicModel(case)
    finer = modal.histories(model, result.t, phase_step=modal.PHASE_STEP / 2).history
    for p in case.probe_names:
        change = np.abs(finer[p] - result.history[p]).max() / np.abs(result.history[p]).max()
        assert stated[p] / 8 < change < stated[p] / 2, (p, change, stated[p])


def test_pulse_needs_no_sampling():
    result = modal.solve(get_case("layered_cylinder", {"load": "pulse", "harmonics": 3, "t_end": 1e-3}))
    assert result.info["load_sampling"] == dict.fromkeys(result.history, 0.0)


# -- what is not built --------------------------------------------------------------------------
def test_forces_are_refused_not_dropped():
    case = dataclasses.replace(get_case("layered_cylinder"), forces=(Force(("0", "1", "0")),))
    assert unsupported_reason(case) == "body forces and tractions are not built"
    with pytest.raises(UnsupportedCase, match="body forces and tractions are not built"):
        modal.solve(case)
