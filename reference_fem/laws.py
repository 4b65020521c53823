"""The material law extension point: the reference's implementation of each law, by name (:data:`LAWS`).

Each law has the shape of :class:`cases.law.MaterialLaw` (and ``tangent``, for Newton) in the
reference's vectors: Mandel, points first ``(n_qp, nc)``; :meth:`stress` takes the total strain
(the reference's formulation) and the committed state, a :class:`reference_fem.plasticity.Return`,
and ``tangent=False`` from the explicit engine (no consistent tangent needed).
A law is made by ``LAWS[material.law](material, dim)``; an unknown law is refused when the
model is built (:func:`get`). Add one with :func:`register`. The numerics are the reference's
own, independent of SMFEM's (:mod:`smfem.laws`).
"""

from __future__ import annotations

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
