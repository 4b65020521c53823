"""The material law extension point: SMFEM's implementation of each law, by name (:data:`LAWS`).

Each law has the shape of :class:`cases.law.MaterialLaw` in SMFEM's vectors (Voigt, engineering
shears, rows first ``(6, n)``); its input to :meth:`stress` is the trial stress
``sigma_n + D d_eps`` of the additional-loads iterations. A law is made by
``LAWS[material.law](material, factor)``, ``factor`` the stiffness factor per point (the cut-outs'
contrast material: 1 elsewhere). An unknown law is refused when the model is built
(:func:`get`). Add one with :func:`register`.

A law may also say how far each trial stress is from leaving its elastic range (``headroom``)
and take its stress at some points only (``stress_at``, ``equivalent_plastic_strain_at``): the
iterations then visit only the points a change may carry past it (:mod:`smfem.screening`); a
law without them is visited at every point.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable

import numpy as np

from cases.material import ELASTIC, VON_MISES, lame, sigma_y_from_tau_s
from cases.params import UnsupportedCase

from .constitutive import isotropic_D
from .plasticity import intensity, return_map_rows, von_mises, yield_stress



@dataclass
class ElasticState:
    sigma: np.ndarray  # (6, n)
    yielding: np.ndarray = field(default_factory=lambda: np.zeros(0, int))


class Elastic:
    """Isotropic elasticity: the stress is the trial."""

    name, nonlinear = ELASTIC, False

    def __init__(self, material, factor=1.0):
        self.material = material

    def elastic_matrix(self) -> np.ndarray:
        return isotropic_D(self.material.E, self.material.nu)

    def initial_state(self, n: int) -> ElasticState:
        return ElasticState(np.zeros((6, n)))

    def trial(self, strain_increment: np.ndarray, state) -> np.ndarray:
        return state.sigma + self.elastic_matrix() @ strain_increment

    def stress(self, trial: np.ndarray, state) -> tuple[np.ndarray, ElasticState]:
        return trial, ElasticState(trial)

    def equivalent_plastic_strain(self, state) -> np.ndarray:
        return np.zeros(state.sigma.shape[1])


@dataclass
class PlasticState:
    """Stresses (6, n), the accumulated equivalent plastic strain ``alpha`` (n,), the plastic
    strains at the start of the step and the step's increments at the points that yield (the
    whole eps_p is formed once, when asked: the iterations need only the increments). ``sigma``
    is None in a state of :meth:`VonMises.stress_at`, whose iterations make each trial stress
    from the amplitudes."""

    sigma: np.ndarray | None
    alpha: np.ndarray
    eps_p0: np.ndarray
    yielding: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    deps_p: np.ndarray | None = None

    @cached_property
    def eps_p(self) -> np.ndarray:
        """The plastic strains (6, n), Voigt with engineering shears."""
        if not len(self.yielding):
            return self.eps_p0
        eps_p = self.eps_p0.copy()
        eps_p[:, self.yielding] += self.deps_p
        return eps_p


class VonMises(Elastic):
    """von Mises plasticity with linear isotropic hardening, Wilkins' correction
    (:mod:`smfem.plasticity`)."""

    name, nonlinear = VON_MISES, True

    def __init__(self, material, factor=1.0):
        super().__init__(material)
        self.mu = lame(material.E, material.nu)[1] * np.asarray(factor, float)
        self.sigma_y0, self.H = material.sigma_y, material.hardening_modulus

    def initial_state(self, n: int) -> PlasticState:
        return PlasticState(np.zeros((6, n)), np.zeros(n), np.zeros((6, n)))

    def stress(self, trial: np.ndarray, state) -> tuple[np.ndarray, PlasticState]:
        mu = self.mu if self.mu.shape == state.alpha.shape else np.broadcast_to(self.mu, state.alpha.shape)
        sigma, alpha, at, deps_p = return_map_rows(trial, state.alpha, mu, self.sigma_y0, self.H)
        return sigma, PlasticState(sigma, alpha, state.eps_p, at, deps_p)

    def equivalent_plastic_strain(self, state) -> np.ndarray:
        return intensity(state.eps_p.T)

    def equivalent_plastic_strain_at(self, state, points: np.ndarray) -> np.ndarray:
        """:meth:`equivalent_plastic_strain` at ``points`` only."""
        return intensity(np.take(state.eps_p, points, axis=1).T)

    def headroom(self, trial: np.ndarray, state) -> np.ndarray:
        """(n,) how far each trial stress is inside the yield surface of the committed
        ``state``, in the von Mises stress (negative where it yields): a trial that moves by
        less stays elastic (:mod:`smfem.screening`)."""
        return yield_stress(state.alpha, self.sigma_y0, self.H) - von_mises(trial)

    def stress_at(self, trial: np.ndarray, state, points: np.ndarray) -> tuple[np.ndarray, PlasticState]:
        """:meth:`stress` at ``points`` (k,) only, ``trial`` (6, k) theirs: every other point
        is known to stay elastic. The state left holds no stresses (``sigma`` None: the
        iterations make each trial from the amplitudes) and its ``yielding`` among all points."""
        mu = self.mu[points] if np.ndim(self.mu) else self.mu
        sigma_y0, H = (v if np.ndim(v) == 0 else v[points] for v in (self.sigma_y0, self.H))
        sigma, alpha, at, deps_p = return_map_rows(trial, state.alpha[points], np.broadcast_to(mu, len(points)),
                                                   sigma_y0, H)
        alpha_all = state.alpha
        if len(at):
            alpha_all = alpha_all.copy()
            alpha_all[points[at]] = alpha[at]
        return sigma, PlasticState(None, alpha_all, state.eps_p, points[at], deps_p)


#: law name -> ``(material, factor) -> law``
LAWS: dict[str, Callable] = {Elastic.name: Elastic, VonMises.name: VonMises}


def register(name: str, make: Callable) -> None:
    """Add (or replace) the law ``name``: ``make(material, factor)`` gives its implementation."""
    LAWS[name] = make


@dataclass(frozen=True)
class PointMaterial:
    """The materials of a section of several, one law, as per-point arrays of their constants
    (the fields of :class:`cases.material.Material`): a law made from it acts point by point."""

    law: str
    E: np.ndarray
    nu: np.ndarray
    rho: np.ndarray
    tau_s: np.ndarray
    E_T: np.ndarray

    @property
    def sigma_y(self) -> np.ndarray:
        return sigma_y_from_tau_s(self.tau_s)

    @property
    def hardening_modulus(self) -> np.ndarray:
        return np.where(self.E_T > 0, self.E * self.E_T / np.where(self.E_T > 0, self.E - self.E_T, 1.0), 0.0)


def for_points(materials, index: np.ndarray, factor=1.0):
    """The law of points made of ``materials[index]`` (one law: :class:`cases.case.Case` checks
    it); a single material's law as :func:`get` makes it."""
    if len(materials) == 1:
        return get(materials[0], factor)
    fields = {name: np.array([getattr(m, name) for m in materials])[index] for name in ("E", "nu", "rho", "tau_s", "E_T")}
    return get(PointMaterial(materials[0].law, **fields), factor)


def get(material, factor=1.0):
    """SMFEM's implementation of ``material``'s law; an unknown law is refused."""
    make = LAWS.get(material.law)
    if make is None:
        raise UnsupportedCase(f"smfem: no material law {material.law!r} (SMFEM's laws: {', '.join(LAWS)})")
    return make(material, factor)
