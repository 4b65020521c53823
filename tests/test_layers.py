"""The architecture (docs/architecture.md) as a test: every module imports only its own package
and the layers below it, and no modules import one another in a circle.

Layers, top to bottom: ``smfem.cli`` -> ``smfem.api`` (and ``smfem/__init__``, its face) ->
``reports`` -> ``smfem.studies`` -> ``smfem.runs`` -> ``smfem`` (the numerics) | ``reference_fem``
(side by side: neither imports the other) -> ``cases``, ``smfem.truths``. A module belongs to the
layer of the longest name above that it starts with. Function-level imports count too. A
``__main__`` module (``python -m smfem``) is an entry point that nothing imports: it belongs to
the top layer wherever it sits.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RANK = {"smfem.cli": 6, "smfem.api": 5, "reports": 4, "smfem.studies": 3, "smfem.runs": 2, "smfem": 1,
        "reference_fem": 1, "cases": 0, "smfem.truths": 0}
#: the ``smfem`` package's ``__init__`` is the public API's face (its names come from smfem.api)
FACE = {"smfem": "smfem.api"}
PACKAGES = {name.split(".")[0] for name in RANK}


def layer(module: str) -> str:
    """The layer (a key of RANK) ``module`` belongs to."""
    return FACE.get(module) or max((k for k in RANK if module == k or module.startswith(k + ".")), key=len)


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(path: Path) -> set[str]:
    """Project modules ``path`` imports (relative imports resolved; ``from p import m`` gives
    ``p.m`` where ``m`` is a module, else ``p``)."""
    here = module_name(path)
    package = here if path.name == "__init__.py" else here.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                base = ".".join(anchor + ([base] if base else []))
            for a in node.names:
                sub = f"{base}.{a.name}"
                found.add(sub if sub in MODULES else base)
    return {m for m in found if m.split(".")[0] in PACKAGES}


SOURCES = sorted(p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py"))
MODULES = {module_name(p) for p in SOURCES}
GRAPH = {module_name(p): imports_of(p) for p in SOURCES}


def test_every_package_is_seen():
    assert {layer(m) for m in MODULES} == set(RANK)
    assert len(MODULES) > 80


@pytest.mark.parametrize("module", sorted(GRAPH))
def test_imports_stay_within_the_layers_below(module):
    own = layer(module)
    rank = max(RANK.values()) + 1 if module.endswith(".__main__") else RANK[own]
    wrong = sorted(d for d in GRAPH[module] if layer(d) != own and RANK[layer(d)] >= rank)
    assert not wrong, f"{module} imports {wrong}: only its own layer and {[p for p in RANK if RANK[p] < rank]}"


def test_nothing_imports_an_entry_point():
    assert not [m for m, deps in GRAPH.items() for d in deps if d.endswith("__main__")]


def test_no_import_cycles():
    """Tarjan's strongly connected components over module -> module imports (a package's
    ``__init__`` counts as a module)."""
    index, low, stack, on, cycles, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in GRAPH.get(v, ()):
            if w not in GRAPH or w == v:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in sorted(GRAPH):
        if v not in index:
            visit(v)
    assert not cycles, cycles
