"""The material law extension point: the reference's implementation of each law, by name (:data:`LAWS`).

Each law has the shape of :class:`cases.law.MaterialLaw` (and ``tangent``, for Newton) in the
reference's vectors: Mandel, points first ``(n_qp, nc)``; :meth:`stress` takes the total strain
(the reference's formulation) and the committed state, a :class:`reference_fem.plasticity.Return`,
and ``tangent=False`` from the explicit engine (no consistent tangent needed).
A law is made by ``LAWS[material.law](material, dim)``; an unknown law is refused when the
model is built (:func:`get`). Add one with :func:`register`. A body of several materials
(``case.regions``) has one law per material, each at its own points (:class:`Regional`). The
numerics are the reference's own, independent of SMFEM's (:mod:`smfem.laws`).
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

from cases.material import ELASTIC, VON_MISES
from cases.params import UnsupportedCase

from . import forms
from .plasticity import Return, equivalent_plastic_strain, radial_return


class Elastic:
    """Isotropic elasticity: ``sigma = D eps``."""

    name, nonlinear = ELASTIC, False

    def __init__(self, material, dim: int):
        self.lam, self.mu = material.lame
        self.D = forms.elastic_matrix(self.lam, self.mu, dim)

    def elastic_matrix(self) -> np.ndarray:
        return self.D

    def initial_state(self, n: int) -> Return:
        nc = self.D.shape[0]
        return Return(np.zeros((n, nc)), None, np.zeros((n, nc)), np.zeros(n), np.zeros(n, bool), np.zeros((n, nc)))

    def trial(self, strain_increment: np.ndarray, state: Return) -> np.ndarray:
        return state.strain + strain_increment

    def stress(self, strain: np.ndarray, state: Return, tangent: bool = True) -> tuple[np.ndarray, Return]:
        sigma = np.einsum("qc,cd->qd", strain, self.D)
        return sigma, Return(sigma, None, state.eps_p, state.alpha, np.zeros(len(strain), bool), strain)

    def tangent(self, state: Return) -> np.ndarray:
        return np.broadcast_to(self.D, (len(state.sigma),) + self.D.shape)

    def equivalent_plastic_strain(self, state: Return) -> np.ndarray:
        return equivalent_plastic_strain(state.eps_p)


class VonMises(Elastic):
    """von Mises plasticity with linear isotropic hardening, radial return
    (:func:`reference_fem.plasticity.radial_return`); ``stress(..., tangent=False)`` skips the
    consistent tangent (an explicit step needs the stress only)."""

    name, nonlinear = VON_MISES, True

    def __init__(self, material, dim: int):
        super().__init__(material, dim)
        self.sigma_y, self.H = material.sigma_y, material.hardening_modulus

    def stress(self, strain: np.ndarray, state: Return, tangent: bool = True) -> tuple[np.ndarray, Return]:
        ret = radial_return(strain, state.eps_p, state.alpha, self.lam, self.mu, self.sigma_y, self.H, tangent=tangent)
        return ret.sigma, ret

    def tangent(self, state: Return) -> np.ndarray:
        return state.tangent


#: law name -> ``(material, dim) -> law``
LAWS: dict[str, Callable] = {Elastic.name: Elastic, VonMises.name: VonMises}


def register(name: str, make: Callable) -> None:
    """Add (or replace) the law ``name``: ``make(material, dim)`` gives its implementation."""
    LAWS[name] = make


def get(material, dim: int):
    """The reference's implementation of ``material``'s law; an unknown law is refused."""
    make = LAWS.get(material.law)
    if make is None:
        raise UnsupportedCase(f"reference FEM: no material law {material.law!r} (its laws: {', '.join(LAWS)})")
    return make(material, dim)


class Regional:
    """Several materials' laws in one body, each at its own points: the shape of one law.

    ``laws[k]`` is material k's law (:func:`get`) and ``index`` ``(n,)`` each point's material.
    The elastic matrix is per point, ``(n, nc, nc)``; the state is the points' states merged
    (each law's own record, a dataclass of arrays with the points first, or None). Every
    material of a case follows the same law (:class:`cases.case.Case` checks it), so the parts'
    states are of one type.
    """

    def __init__(self, laws: list, index: np.ndarray):
        self.n = index.size
        parts = [(law, np.flatnonzero(index == k)) for k, law in enumerate(laws)]
        #: ``(law, its points)`` of every material with points
        self.parts = [(law, points) for law, points in parts if points.size]
        self.name = self.parts[0][0].name
        self.nonlinear = any(law.nonlinear for law, _ in self.parts)
        nc = laws[0].elastic_matrix().shape[-1]
        self.D = np.empty((self.n, nc, nc))
        for law, points in self.parts:
            self.D[points] = law.elastic_matrix()

    def elastic_matrix(self) -> np.ndarray:
        return self.D

    def _merged(self, states: list):
        """One state of all points from the parts' states (in the order of :attr:`parts`)."""
        fields = {}
        for f in dataclasses.fields(states[0]):
            values = [getattr(s, f.name) for s in states]
            if values[0] is None:
                fields[f.name] = None
                continue
            out = np.empty((self.n,) + values[0].shape[1:], values[0].dtype)
            for (_, points), v in zip(self.parts, values):
                out[points] = v
            fields[f.name] = out
        return type(states[0])(**fields)

    @staticmethod
    def _taken(state, points: np.ndarray):
        """``state`` at ``points`` only."""
        values = {f.name: getattr(state, f.name) for f in dataclasses.fields(state)}
        return dataclasses.replace(state, **{k: v[points] for k, v in values.items() if v is not None})

    def initial_state(self, n: int):
        if n != self.n:
            raise ValueError(f"regional law of {self.n} points asked for the state of {n}")
        return self._merged([law.initial_state(points.size) for law, points in self.parts])

    def trial(self, strain_increment: np.ndarray, state) -> np.ndarray:
        out = np.empty_like(strain_increment)
        for law, points in self.parts:
            out[points] = law.trial(strain_increment[points], self._taken(state, points))
        return out

    def stress(self, strain: np.ndarray, state, tangent: bool = True):
        states = [law.stress(strain[points], self._taken(state, points), tangent=tangent)[1]
                  for law, points in self.parts]
        merged = self._merged(states)
        return merged.sigma, merged

    def tangent(self, state) -> np.ndarray:
        out = np.empty_like(self.D)
        for law, points in self.parts:
            out[points] = law.tangent(self._taken(state, points))
        return out

    def equivalent_plastic_strain(self, state) -> np.ndarray:
        out = np.empty(self.n)
        for law, points in self.parts:
            out[points] = law.equivalent_plastic_strain(self._taken(state, points))
        return out


def regional(materials, dim: int, index: np.ndarray) -> Regional:
    """The law of a body of several ``materials`` (``case.materials``), point ``q`` of material
    ``index[q]``; each material's law as :func:`get` makes it (an unknown one is refused)."""
    return Regional([get(m, dim) for m in materials], index)
