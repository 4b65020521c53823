"""The reference's own numerical checks, for the stability study (reached through the solver
table, ``smfem.runs.registry.checks('reference')``): the static solution's probes."""

from __future__ import annotations

from .probes import Probes
from .solver import static


def static_probes(case) -> dict:
    """The static solution under the case's loads: probe name -> value."""
    model, (u,), _, system = static(case)
    return dict(zip([p.name for p in case.probes], Probes(model).values(u, system)))
