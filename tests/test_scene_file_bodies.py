"""Scene files of several bodies in contact (docs/scenes.md, "Scenes from a file": ``[[bodies]]``,
``[[contact]]``, ``region``; issue 39): the example file is the built-in ``rod_collision`` at any
parameters, a body's own material is a region of it, and every mistake is one line naming the
file and the key, exit status 2, nothing written (the example as the built-in, field by field and
history by history: tests/test_scene_file.py; mutated at random: tests/test_scene_file_fuzz.py)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from cases import get_case, rebuild
from cases.geometry import ContactPair, Pressure, Region, Support
from cases.material import Material
from cases.scene_file import from_text
from smfem.cli import main
from tests.test_scene_file_fuzz import FAST, dumps, mutate, read

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "rod_collision.toml"
TEXT = EXAMPLE.read_text()
#: what a solver reads of a Case
FIELDS = ("name", "body", "section", "material", "loads", "supports", "probes", "params", "length", "cutouts",
          "initial_velocity", "wall", "symmetric", "axisymmetric", "regions", "contacts")
TARGET = 't = { breaks = [0.0, 1.0], counts = [100] }'
CONTACT = 'face = "target.face"\nother = "striker.face"\nfriction = "friction"\n'


def edited(old: str, new: str, text: str = TEXT) -> str:
    """``text`` with its one ``old`` replaced by ``new``."""
    assert text.count(old) == 1, old
    return text.replace(old, new)


def without_contact(text: str = TEXT) -> str:
    return edited("[[contact]]", "[[unused]]", text).replace(CONTACT, "").replace("[[unused]]", "")


@pytest.mark.parametrize("overrides", [{}, {"v0": 2.0, "friction": 0.3, "layer_stiffness": 10.0, "refine": 2}])
def test_the_example_is_the_builtin_scene_at_any_parameters(overrides):
    builtin, case = get_case("rod_collision", overrides), get_case(EXAMPLE, overrides)
    assert all(getattr(case, f) == getattr(builtin, f) for f in FIELDS)
    again, builtin = rebuild(case, {"v0": 1.0}), get_case("rod_collision", {**overrides, "v0": 1.0})
    assert all(getattr(again, f) == getattr(builtin, f) for f in FIELDS)


def test_the_pieces_of_several_bodies_are_read():
    case = get_case(EXAMPLE)
    assert tuple(case.section.regions) == ("striker", "target") and "striker.face" in case.section.edges
    assert case.contacts == (ContactPair("target.face", "striker.face", 0.0, 0.0),)
    assert case.initial_velocity[0].region == "striker"
    assert [p.region for p in case.probes if p.kind == "body_mean"] == ["striker", "target"]


def test_a_body_of_its_own_material_is_a_region_of_it():
    text = edited('name = "target"\n', 'name = "target"\nE = 1.1e11\nnu = 0.34\nrho = 8.8e3\n')
    case = from_text(text, "bronze.toml")
    assert case.regions == (Region("target", Material(1.1e11, 0.34, 8.8e3, 1.7e8)),)
    assert case.material == get_case("rod_collision").material


def test_loads_and_supports_name_the_edges_of_the_bodies():
    load = '[[load]]\nq = 1e6\nedge = "striker.end"\nmode = 0\n'
    text = f'{TEXT}\n{load}\n[[support]]\nedge = "target.end"\ncomponents = [2]\n'
    case = from_text(text, "held.toml")
    assert case.loads == (Pressure(1e6, "striker.end", (), 0),) and case.supports == (Support("target.end", (2,)),)


def test_a_stated_interference_allows_that_overlap():
    """The target moved 1 mm into the striker, the pair stating that interference (without it:
    refused, below)."""
    moved = edited(TARGET, 't = { breaks = [-0.001, 0.999], counts = [100] }')
    moved = edited("point = [0.0, 1.0, 0.0]", "point = [0.0, 0.999, 0.0]", moved)
    case = from_text(edited(CONTACT, CONTACT + "interference = 0.001\n", moved), "fit.toml")
    assert case.contacts[0].interference == 0.001


def test_a_scene_of_several_bodies_without_contact_needs_no_layer():
    text = without_contact()
    for key in ("layer_thickness = 1e-4", "layer_stiffness = 1.0", "friction = 0.0\n"):
        text = text.replace(key, "#")
    assert from_text(text, "apart.toml").contacts == ()


IMPACT = (EXAMPLE.parent / "rod_impact.toml").read_text()
#: the example with the target's table cut out: one body
ONE_BODY = TEXT.split("[[bodies]]                     # the target")[0] + "[[contact]]" + TEXT.split("[[contact]]")[1]
#: rod_impact without its [section]
NO_SECTION = IMPACT.split("[section]")[0] + "[[initial_velocity]]" + IMPACT.split("[[initial_velocity]]")[1]
OVERLAP = edited(TARGET, 't = { breaks = [-0.001, 0.999], counts = [100] }')
APART = edited(TARGET, 't = { breaks = [0.2, 1.2], counts = [100] }')
#: the target's radius in 4 elements, the striker's in 5: the faces' nodes are not across each other
MISMATCHED = edited('counts = [5] }\n' + TARGET, 'counts = [4] }\n' + TARGET)
NO_LAYER_USE = without_contact().replace("friction = 0.0\n", "")


@pytest.mark.parametrize(
    "text,needle",
    [
        (edited("[references]", '[section]\nkind = "rect"\n\n[references]'), "bodies: give either [section]"),
        (NO_SECTION, "section: give either [section] (one body) or [[bodies]] (several), missing both"),
        (TEXT.replace("[[bodies]]", "[[bodys]]"), "bodys: unknown key"),
        (ONE_BODY, "bodies: 1 given: a scene of several bodies needs at least two"),
        (edited('body = "ring"', "# ring").replace("[[bodies]]", "[[body]]"), 'body: write body = "ring"'),
        (edited('name = "striker"\n', ""), "bodies[1].name: missing"),
        (edited('name = "target"\n', 'name = "striker"\n'), "bodies[2].name: 'striker'"),
        (edited('name = "target"\n', 'name = "tar.get"\n'), "bodies[2].name: 'tar.get'"),
        (edited('name = "target"\nkind = "rect"', 'name = "target"\nkind = "mesh"'), "bodies[2].kind: 'mesh'"),
        (edited('name = "target"\n', 'name = "target"\nE_T = 3e11\n'), "bodies[2].E_T"),
        (edited('face = "target.face"', 'face = "target.nose"'), "contact[1].face: 'target.nose': choose one of"),
        (edited('face = "target.face"', 'face = "face"'), "contact[1].face: 'face'"),  # a block's edge alone
        (edited('face = "target.face"', 'face = "striker.end"'), "contact[1].other: 'striker.face' is of the body"),
        (TEXT + '\n[[contact]]\nface = "striker.face"\nother = "target.end"\n',
         "contact[2].face: 'striker.face' is in contact[1] already"),
        (OVERLAP, "contact[1]: contact pair target.face / striker.face: the bodies overlap by 0.001"),
        (APART, "contact[1]: contact pair target.face / striker.face: the faces are 0.2 apart"),
        (MISMATCHED, "contact[1]: contact pair target.face / striker.face: the face borders nothing"),
        (edited(CONTACT, CONTACT + "interference = -1e-3\n"), "contact[1].interference"),
        (IMPACT + '\n[[contact]]\nface = "face"\nother = "face"\n', "contact: a contact pair joins two bodies"),
        (edited('region = "target"', 'region = "anvil"'), "probe[4].region: 'anvil' is not a body of the scene"),
        (edited('value = "v0"\nregion = "striker"', 'value = "v0"\nregion = "hammer"'),
         "initial_velocity[1].region: 'hammer' is not a body"),
        (edited("point = [0.0, 0.5, 0.0]", 'point = [0.0, 0.5, 0.0]\nregion = "target"'),
         "probe[2].region: not for a point probe"),
        (edited('value = "-v0"', 'value = "-v0"\nregion = "rod"', IMPACT), "initial_velocity[1].region: one mapped block"),
        (TEXT + '\n[[region]]\nname = "target"\nE = 1e11\n', "region: not with [[bodies]]"),
        (edited("layer_thickness = 1e-4", "#"), "params.layer_thickness: missing (a scene with [[contact]] needs it)"),
        (NO_LAYER_USE, "params.layer_thickness: the scene has no [wall] or [[contact]] to use it"),
        (edited('edge = "target.face"', 'edge = "t_min"'), "probe[1].edge: 't_min'"),  # the bodies' edges only
    ],
)
def test_a_mistake_in_a_scene_of_bodies_is_one_line(tmp_path, capsys, text, needle):
    scene, out = tmp_path / "scene.toml", tmp_path / "out"
    scene.write_text(text)
    assert main(["run", str(scene), "--out", str(out), "--quiet", "--no-fields"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith(f"smfem: error: {scene}: ") and needle in err, err
    assert "Traceback" not in err and not out.exists()


def test_the_example_runs_from_the_command_line(tmp_path):
    out = tmp_path / "out"
    assert main(["run", str(EXAMPLE), "--out", str(out), "--quiet", "--no-fields", "--set", "t_end=3e-6"]) == 0
    header = (out / "history.csv").read_text().splitlines()[0]
    assert header.split(",") == ["t", *get_case(EXAMPLE).probe_names] and (out / "summary.json").exists()


@pytest.fixture(scope="module")
def marker(tmp_path_factory) -> Path:
    """A file that nothing in a scene may create (tests/test_scene_file_fuzz.py)."""
    return tmp_path_factory.mktemp("fuzz") / "MARKER"


@FAST
@given(data=st.data())
def test_a_mutated_scene_of_bodies_is_a_case_or_one_line(marker, data):
    """The fuzz test's mutations, all of them on the scene of two bodies."""
    read(mutate(data, tomllib.loads(TEXT)), marker)


def test_the_writer_round_trips_the_bodies_scene():
    assert tomllib.loads(dumps(tomllib.loads(TEXT))) == tomllib.loads(TEXT)
