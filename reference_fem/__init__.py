"""Independent reference solver for the verification cases (scikit-fem, quadratic elements).

>>> from cases import get_case
>>> from reference_fem import solve
>>> result = solve(get_case("dome"))            # 2D axisymmetric
>>> result = solve(get_case("dome", {"dim": 3}))  # full 3D cap
>>> result = solve(get_case("rod_impact"))      # contact with a rigid wall

Contact is node-to-wall with Lagrange multipliers and an active set (:mod:`.contact`), the
contact nodes made massless by mass redistribution (:mod:`.mass`); between two bodies
(``rod_collision``) node-to-node on the same rows and active set (:mod:`.pairs`).

Imports nothing from :mod:`smfem`; sees a scene only through :mod:`cases`.
"""

from .model import Model
from .solver import solve, static

__all__ = ["Model", "solve", "static"]
