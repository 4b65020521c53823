"""The shape every solver's implementation of a material law has: :class:`MaterialLaw`.

A description only (the data layer holds no numerics): each solver implements each law in its
own module and table (SMFEM: :mod:`smfem.laws`; the reference: :mod:`reference_fem.laws`), so
the reference stays an independent check. The shape is shared so that a law is added the same
way in both and a test can drive both implementations along one strain path.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np


class MaterialLaw(Protocol):
    """One constitutive law at ``n`` points at once, in its solver's own vectors: SMFEM's Voigt
    rows first, ``(6, n)``, engineering shears; the reference's Mandel vectors points first,
    ``(n, nc)``. The state is the law's own record (the solver keeps it, passes it back and
    commits it once a step has converged); it has ``sigma``, the stress, and ``yielding``, the
    points whose inelastic state the last :meth:`stress` changed (empty for an elastic law).

    Attributes
    ----------
    name : the :attr:`cases.material.Material.law` it implements
    nonlinear : whether the stress depends on the state: the solvers' iterative paths; False means
        ``stress = elastic_matrix() strain`` and the linear paths, which need nothing else
    """

    name: str
    nonlinear: bool

    def elastic_matrix(self) -> np.ndarray:
        """The elasticity matrix ``(c, c)`` in the solver's components."""

    def initial_state(self, n: int) -> Any:
        """The unstrained state at ``n`` points."""

    def trial(self, strain_increment: np.ndarray, state) -> np.ndarray:
        """The elastic predictor of a step's strain increment from ``state``, as :meth:`stress`
        takes it: SMFEM's trial stress ``sigma + D d_eps`` (its iterations make it from the
        amplitudes directly), the reference's total strain ``eps + d_eps``."""

    def stress(self, trial: np.ndarray, state) -> tuple[np.ndarray, Any]:
        """The stress the step reaches from the committed ``state`` and the state it leaves
        (the return map): ``(stress, new_state)``."""

    def equivalent_plastic_strain(self, state) -> np.ndarray:
        """``sqrt(2/3 eps_p : eps_p)`` per point, ``(n,)`` (the probes' ``peps``)."""


class LinearisedLaw(MaterialLaw, Protocol):
    """A law a Newton solver linearises (the reference's implicit equilibrium); SMFEM's
    additional-loads iterations use the elastic matrix alone."""

    def tangent(self, state) -> np.ndarray:
        """The consistent tangent ``d sigma / d eps`` per point, ``(n, c, c)``, of the state
        :meth:`stress` left."""
