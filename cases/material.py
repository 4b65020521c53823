"""Material constants, the constitutive law they make, and the one place that converts between them.

A material's :attr:`Material.law` names its law; each solver implements every law in its own
table (SMFEM: :mod:`smfem.laws`; the reference: :mod:`reference_fem.laws`), in the shape of
:class:`cases.law.MaterialLaw`, and the CalculiX deck writes its cards by the same name.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: the laws a :class:`Material` is (its ``law``): isotropic elasticity; von Mises plasticity with
#: linear isotropic hardening (``E_T``; 0 = ideal plasticity) on top of it
ELASTIC, VON_MISES = "elastic", "von-mises-linear-hardening"


@dataclass(frozen=True)
class Material:
    """Isotropic material; SI or any consistent units.

    ``tau_s`` is the yield stress in pure shear (von Mises: ``sigma_y = sqrt(3) tau_s``);
    ``E_T`` the tangent modulus of linear isotropic hardening (0 = ideal plasticity).
    ``plastic=False`` means the yield limit is ignored.
    """

    E: float
    nu: float
    rho: float
    tau_s: float = math.inf
    E_T: float = 0.0
    plastic: bool = False

    @property
    def law(self) -> str:
        """The constitutive law's name, derived (not a field: the stored truths' keys hash the
        fields). Data for another law is another dataclass in ``cases/`` with its own ``law``."""
        return VON_MISES if self.plastic else ELASTIC

    @property
    def lame(self) -> tuple[float, float]:
        return lame(self.E, self.nu)

    @property
    def sigma_y(self) -> float:
        return sigma_y_from_tau_s(self.tau_s)

    @property
    def hardening_modulus(self) -> float:
        """Plastic modulus H = E E_T / (E - E_T) in sigma_y = sigma_y0 + H eps_p."""
        return hardening_modulus(self.E, self.E_T)

    @property
    def wave_speed(self) -> float:
        """Bar wave speed sqrt(E / rho)."""
        return math.sqrt(self.E / self.rho)


def lame(E: float, nu: float) -> tuple[float, float]:
    """Lame constants ``(lambda, mu)`` from Young's modulus and Poisson's ratio."""
    return E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))


def young_poisson(lam: float, mu: float) -> tuple[float, float]:
    """Inverse of :func:`lame`: ``(E, nu)`` from ``(lambda, mu)``."""
    return mu * (3 * lam + 2 * mu) / (lam + mu), lam / (2 * (lam + mu))


def sigma_y_from_tau_s(tau_s: float) -> float:
    return math.sqrt(3.0) * tau_s


def tau_s_from_sigma_y(sigma_y: float) -> float:
    return sigma_y / math.sqrt(3.0)


def hardening_modulus(E: float, E_T: float) -> float:
    return E * E_T / (E - E_T) if E_T else 0.0
