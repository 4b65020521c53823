"""The verification scenes as data (docs/scenes.md), and scenes from TOML files
(:mod:`cases.scene_file`). No solver imports here.

>>> from cases import get_case
>>> case = get_case("thick_cylinder", {"dt": 1e-5})
>>> mine = get_case("examples/dome.toml", {"dt": 1e-5})
"""

from pathlib import Path

from . import dome, flywheel, layered_cylinder, moving_load, notched_cylinder, notched_strip, ring_in_ring, rod_collision, rod_impact, scene_file, thick_cylinder
from .case import Case
from .params import ParameterError, UnsupportedCase, parse_sets, validate

_MODULES = (dome, thick_cylinder, notched_cylinder, notched_strip, rod_impact, layered_cylinder, flywheel, moving_load, rod_collision, ring_in_ring)
CASES = {m.NAME: m for m in _MODULES}
#: scenes that are a built-in scene at other parameters, under their own name (their stored
#: truth, example file and report section): the scene builds a case of this name whenever its
#: parameters are these
VARIANTS = {layered_cylinder.PULSE_NAME: (layered_cylinder.NAME, {"load": "pulse"}),
            moving_load.NOTCHED_NAME: (moving_load.NAME, moving_load.NOTCHED)}


def get_case(name: str | Path, overrides: dict | None = None) -> Case:
    """Build case ``name`` with validated ``overrides`` (keys and values: docs/scenes.md);
    a ``name`` ending in ``.toml`` is a scene file (docs/scenes.md, "Scenes from a file");
    a name of :data:`VARIANTS` is its scene at its parameters (the overrides on top)."""
    if str(name).lower().endswith(".toml"):
        return scene_file.load(name, overrides)
    if name in VARIANTS:
        name, fixed = VARIANTS[name]
        overrides = {**fixed, **(overrides or {})}
    if name not in CASES:
        raise ParameterError(f"unknown case {name!r}: choose one of {', '.join([*CASES, *VARIANTS])} or give a "
                             "scene file NAME.toml")
    module = CASES[name]
    return module.build(validate(module.SPECS, module.DEFAULTS, overrides or {}, name))


def rebuild(case: Case, overrides: dict | None = None) -> Case:
    """``case`` built again from its source with ``case.params`` updated by ``overrides``: a
    built-in scene by its name, a file scene from the text it was read from (the file is not
    read again)."""
    params = {**case.params, **(overrides or {})}
    if case.source is not None:
        return scene_file.from_text(case.source.text, case.source.path, params)
    return get_case(case.name, params)


__all__ = ["CASES", "VARIANTS", "Case", "ParameterError", "UnsupportedCase", "get_case", "parse_sets", "rebuild"]
