"""The repository's own documents keep up with the code: every parameter of every scene is in
docs/scenes.md, every subcommand and option of the command line in docs/contract.md."""

from __future__ import annotations

from pathlib import Path

import pytest

from cases import CASES
from smfem.cli import build_parser

DOCS = Path(__file__).resolve().parents[1] / "docs"


@pytest.mark.parametrize("name", CASES)
def test_every_parameter_of_the_scene_is_documented(name):
    text = (DOCS / "scenes.md").read_text()
    assert f"`{name}`" in text
    assert not [k for k in CASES[name].SPECS if f"`{k}`" not in text]


def test_every_subcommand_and_option_is_in_the_contract():
    text = (DOCS / "contract.md").read_text()
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    for command, parser in sub.choices.items():
        assert f"smfem {command}" in text, command
        options = [o for a in parser._actions for o in a.option_strings if o.startswith("--") and o != "--help"]
        assert not [o for o in options if o not in text], (command, options)


def test_the_architecture_names_every_package():
    text = (DOCS / "architecture.md").read_text()
    assert all(f"{p}/" in text for p in ("smfem/cli", "reports", "smfem/studies", "smfem/runs", "smfem",
                                         "reference_fem", "cases", "smfem/truths"))
    assert "smfem/api.py" in text


def test_every_name_of_the_python_interface_is_in_the_contract():
    import smfem

    text = (DOCS / "contract.md").read_text()
    assert not [n for n in smfem.__all__ if n != "__version__" and f"smfem.{n}" not in text]
