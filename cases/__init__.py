"""The five verification scenes as data (docs/scenes.md). No solver imports here.

>>> from cases import get_case
>>> case = get_case("thick_cylinder", {"dt": 1e-5})
"""

from . import dome, notched_cylinder, notched_strip, rod_impact, thick_cylinder
from .case import Case
from .params import ParameterError, UnsupportedCase, parse_sets, validate

_MODULES = (dome, thick_cylinder, notched_cylinder, notched_strip, rod_impact)
CASES = {m.NAME: m for m in _MODULES}


def get_case(name: str, overrides: dict | None = None) -> Case:
    """Build case ``name`` with validated ``overrides`` (keys and values: docs/scenes.md)."""
    if name not in CASES:
        raise ParameterError(f"unknown case {name!r}: choose one of {', '.join(CASES)}")
    module = CASES[name]
    return module.build(validate(module.SPECS, module.DEFAULTS, overrides or {}, name))


__all__ = ["CASES", "Case", "ParameterError", "UnsupportedCase", "get_case", "parse_sets"]
