"""``smfem cases``: the five scenes, their parameters, defaults and ranges."""

from __future__ import annotations

from cases import CASES, VARIANTS


def add(sub) -> None:
    sub.add_parser("cases", help="list cases, their variants and parameters").set_defaults(handler=command)


def list_cases() -> str:
    lines = []
    for name, module in CASES.items():
        lines.append(f"{name}: {module.TITLE}")
        for key, spec in module.SPECS.items():
            default = module.DEFAULTS.get(key)
            lines.append(f"    {key:<12} default {default!s:<22} {spec.describe()}  {spec.help}")
    for name, (scene, params) in VARIANTS.items():
        lines.append(f"{name}: {scene} with " + ", ".join(f"{k}={v}" for k, v in params.items()))
    return "\n".join(lines)


def command(args) -> int:
    print(list_cases())
    return 0
