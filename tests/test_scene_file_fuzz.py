"""Scene files mutated at random (hypothesis): whatever a file holds, reading it gives a Case or
one :class:`cases.ParameterError` of one line that names the file, never another exception, and
nothing in it runs (docs/scenes.md, "Scenes from a file"; issue 36).

The mutations start from the example files (a scene of two bodies in contact among them,
tests/test_scene_file_bodies.py mutates it alone) and two with a body force and a traction: keys
renamed, deleted or added, values replaced by TOML values of any type, and expressions replaced
by random text or by commands that would create a marker file. Each mutated document is written
back as TOML (a small writer below) and read by :func:`cases.scene_file.from_text`, which runs
nothing. The default run is short and derandomized (the same examples on every machine); the
``slow`` ones try ten times as many.
"""

from __future__ import annotations

import copy
import datetime
import math
import tomllib
import warnings
from pathlib import Path
from typing import NamedTuple

import pytest
from hypothesis import HealthCheck, event, given, settings, strategies as st

from cases import Case, ParameterError
from cases.scene_file import from_text

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
FILE = "fuzz.toml"
#: a ring (symmetric about x3 = 0, as its loads) and a prism, each with a body force and a traction
FORCES = {
    "thick_cylinder": {
        "body_force": [{"pattern": ["0", "-7.8e4 * (1 + 0.2 * cos(2 * x3))", "sin(x3)"], "time": "1 - cos(3.0*t)"}],
        "traction": [{"edge": "outer", "pattern": ["x1 * cos(x3)", "0", "0"], "time": "t"}],
    },
    "notched_strip": {
        "body_force": [{"pattern": ["0", "-9.81 * 7800", "0"]}],
        "traction": [{"edge": "top", "pattern": ["0", "-1e6 * sin(pi * x3 / 0.3)", "0"], "time": "t / 3.2e-4"}],
    },
}


def _documents() -> list[dict]:
    """The example files, then the two with forces, as tomllib reads them."""
    docs = [tomllib.loads(p.read_text()) for p in sorted(EXAMPLES.glob("*.toml"))]
    return docs + [{**tomllib.loads((EXAMPLES / f"{name}.toml").read_text()), **forces}
                   for name, forces in FORCES.items()]


DOCUMENTS = _documents()
#: characters and pieces expressions are made of, and some that are not
TOKENS = ["x1", "x2", "x3", "t", "pi", "E", "I", "y", "sin(", "cos(", "exp(", "log(", "sqrt(", "Heaviside(", "abs(",
          "(", ")", "+", "-", "*", "/", "**", "^", "//", "%", ",", ".", "0", "1", "2.5", "1e308", "1e-400", "10",
          "9", "99999999999999999999", "j", "e", "_", " ", "'", '"', "[", "]", "{", "}", ":", "=", "lambda",
          "if", "else", "or", "__class__", "__import__", "os", "system", "open", "\\", "\n", "\t", "\x00", "é"]
#: commands that would create the marker file ({marker}) if an expression ran as Python
PAYLOADS = ["__import__('os').system('touch {marker}') or 0", "__import__('pathlib').Path('{marker}').touch()",
            "open('{marker}', 'w').close() or x1", "exec(\"open('{marker}', 'w')\")",
            "[open('{marker}', 'w') for _ in (1,)][0] and 0", "x1 if open('{marker}', 'w') else 0",
            "sin(x1).__class__.__init__.__globals__['__builtins__']['open']('{marker}', 'w')",
            "(lambda: __import__('os').system('touch {marker}'))()"]


@pytest.fixture(scope="module")
def marker(tmp_path_factory) -> Path:
    """A file that only a payload that ran would create."""
    return tmp_path_factory.mktemp("fuzz") / "MARKER"


def toml_string(text: str) -> str:
    """A TOML basic string: quotes, backslashes and control characters escaped."""
    escaped = "".join(c if c not in '"\\' and c >= " " and c != "\x7f" else
                      {'"': '\\"', "\\": "\\\\"}.get(c, f"\\u{ord(c):04x}") for c in text)
    return f'"{escaped}"'


class Nested(NamedTuple):
    """``value`` inside ``depth`` arrays or inline tables: written without recursion, so that a
    nesting deeper than Python's recursion limit reaches the reader (found: 5000 arrays deep
    ended in a RecursionError traceback)."""

    value: object
    depth: int
    table: bool


def toml_value(value) -> str:
    """One TOML value on one line (tables inline) of what :func:`values` makes."""
    if isinstance(value, Nested):
        opening, closing = ('{"a" = ', "}") if value.table else ("[", "]")
        return opening * value.depth + toml_value(value.value) + closing * value.depth
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf") if math.isinf(value) else repr(value)
    if isinstance(value, str):
        return toml_string(value)
    if isinstance(value, (datetime.date, datetime.time)):  # datetime is a date
        return value.isoformat()
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    return "{" + ", ".join(f"{toml_string(k)} = {toml_value(v)}" for k, v in value.items()) + "}"


def dumps(doc: dict) -> str:
    return "".join(f"{toml_string(k)} = {toml_value(v)}\n" for k, v in doc.items())


def test_the_writer_round_trips_every_document():
    for doc in DOCUMENTS:
        assert tomllib.loads(dumps(doc)) == doc


text_values = st.text(st.characters(blacklist_categories=("Cs",)), max_size=20)
#: random text of expression pieces (mostly not an expression), and well-formed formulas that
#: reach sympy, the limits on numbers and powers, and numpy
pieces = st.lists(st.sampled_from(TOKENS), max_size=12).map("".join)
formulas = st.recursive(
    st.sampled_from(["x1", "x2", "x3", "t", "pi", "E", "0", "1", "2", "0.5", "-1", "1e308", "1e-308", "10**100",
                     "9**9", "2**1023"]),
    lambda inner: st.one_of(
        st.tuples(inner, st.sampled_from(["+", "-", "*", "/", "**", "^"]), inner).map(lambda f: f"({' '.join(f)})"),
        st.tuples(st.sampled_from(["sin", "cos", "tan", "exp", "log", "sqrt", "abs", "Abs", "tanh", "sinh", "cosh",
                                   "atan", "Heaviside"]), st.lists(inner, min_size=1, max_size=2))
        .map(lambda f: f"{f[0]}({', '.join(f[1])})"),
        inner.map(lambda f: f"-{f}")),
    max_leaves=10)
expressions = pieces | formulas
scalars = st.one_of(
    text_values, expressions, st.sampled_from(["q", "-q", "all", "top", "t_max", "ring", "prism", "point", "u"]),
    st.integers(-2**63, 2**63 - 1), st.sampled_from([0, 1, 2, 3, -1, 2000, 10_001, 2**63 - 1]),
    st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([0.0, -0.0, 1e-300, 1e300, 0.5, 1.0]),
    st.booleans(), st.dates(), st.datetimes(), st.times())
values = st.recursive(scalars, lambda inner: st.lists(inner, max_size=4) | st.dictionaries(text_values, inner, max_size=3),
                      max_leaves=8)


def pick(data, doc):
    """A container in ``doc`` and one of its keys or indices, found by a random walk down."""
    node = doc
    while True:
        keys = list(node) if isinstance(node, dict) else list(range(len(node)))
        if not keys:
            return node, None
        key = data.draw(st.sampled_from(keys))
        if not isinstance(node[key], (dict, list)) or data.draw(st.booleans()):
            return node, key
        node = node[key]


#: what a number is nudged by: to the edges of its range, or past them
NUDGES = [-1, 0, 0.5, 2, 10, 1e-300, 1e300, math.inf, math.nan]


def nudged(value, factor):
    """``value`` times ``factor``: an int stays an int (within TOML's 64 bits), a bool flips."""
    if isinstance(value, bool):
        return not value
    scaled = value * factor
    if isinstance(value, int):
        return int(max(-2**63, min(2**63 - 1, scaled))) if math.isfinite(scaled) else 2**63 - 1
    return scaled


#: how deep a value is nested: as a scene file may, a little or far deeper, and past what a
#: recursive reader takes
DEPTHS = [1, 3, 20, 300, 5000]


def mutate(data, doc: dict) -> dict:
    """One to three random edits of a copy of ``doc``: delete, rename, add, replace a value,
    nudge a number (which more often leaves the rest of the file valid) or nest a value deeply."""
    doc = copy.deepcopy(doc)
    for _ in range(data.draw(st.integers(1, 3))):
        node, key = pick(data, doc)
        edit = data.draw(st.sampled_from(["delete", "rename", "add", "replace", "nudge", "nest"]))
        if edit == "nudge" and key is not None and isinstance(node[key], (int, float)):
            node[key] = nudged(node[key], data.draw(st.sampled_from(NUDGES)))
        elif edit == "nest" and key is not None:
            node[key] = Nested(node[key], data.draw(st.sampled_from(DEPTHS)), data.draw(st.booleans()))
        elif key is None or edit == "add":
            if isinstance(node, dict):
                node[data.draw(text_values | st.sampled_from(["edge", "time", "pattern", "mode", "kind"]))] = \
                    data.draw(values)
            else:
                node.append(data.draw(values))
        elif edit == "delete":
            del node[key]
        elif edit == "rename" and isinstance(node, dict):
            node[data.draw(text_values)] = node.pop(key)
        else:
            node[key] = data.draw(values)
    return doc


def read(doc: dict, marker: Path) -> None:
    """The document read from its TOML: a Case or one line naming the file; nothing ran, and
    Python's parser said nothing on stderr ("invalid decimal literal")."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", SyntaxWarning)
            assert isinstance(from_text(dumps(doc), FILE), Case)
        event("a case")
    except ParameterError as exc:
        event("refused")
        message = str(exc)
        assert len(message.splitlines()) == 1 and message.startswith(f"{FILE}: "), message
    assert not marker.exists()


def expression_slots(doc: dict) -> list[tuple[list | dict, int | str]]:
    """Where a document holds expressions: each force's pattern components and time."""
    slots = []
    for table in ("body_force", "traction"):
        for force in doc.get(table, []):
            slots += [(force["pattern"], i) for i in range(3)] + [(force, "time")]
    return slots


def check_mutations(data, marker):
    read(mutate(data, data.draw(st.sampled_from(DOCUMENTS))), marker)


def check_expressions(data, marker):
    doc = copy.deepcopy(data.draw(st.sampled_from(DOCUMENTS[-len(FORCES):])))
    for _ in range(data.draw(st.integers(1, 2))):
        node, key = data.draw(st.sampled_from(expression_slots(doc)))
        payload = st.sampled_from(PAYLOADS).map(lambda p: p.format(marker=marker))
        node[key] = data.draw(st.one_of(expressions, payload, text_values))
    read(doc, marker)


FAST = settings(max_examples=150, deadline=None, derandomize=True, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
SLOW = settings(FAST, max_examples=1500)


@FAST
@given(data=st.data())
def test_a_mutated_scene_is_a_case_or_one_line(marker, data):
    check_mutations(data, marker)


@FAST
@given(data=st.data())
def test_a_random_expression_is_a_case_or_one_line_and_never_runs(marker, data):
    check_expressions(data, marker)


@pytest.mark.slow
@SLOW
@given(data=st.data())
def test_many_mutated_scenes(marker, data):
    check_mutations(data, marker)


@pytest.mark.slow
@SLOW
@given(data=st.data())
def test_many_random_expressions(marker, data):
    check_expressions(data, marker)


@pytest.mark.parametrize("separator", ["\x1e", "\x0b", "\x0c", "\x85", "\u2028", "\u202e"])
def test_a_line_break_in_a_key_or_a_value_is_escaped(separator):
    """Found by the fuzzer: an unknown key named "\\x1e" gave two lines (str.splitlines breaks at
    more than \\n and \\r), and "\\u202e" would turn the rest of a terminal line around."""
    for doc in ({**DOCUMENTS[0], f"key{separator}": 1}, {**DOCUMENTS[0], "name": f"dome{separator}"}):
        with pytest.raises(ParameterError) as refusal:
            from_text(dumps(doc), FILE)
        message = str(refusal.value)
        assert len(message.splitlines()) == 1 and separator not in message, message


@pytest.mark.parametrize("table", [False, True])
@pytest.mark.parametrize("depth", [17, 300, 5000])
def test_a_deeply_nested_value_is_one_line(depth, table):
    """Arrays or inline tables nested past the scene's schema (MAX_DEPTH) or past the reader's
    recursion: one line naming the file, as every other reading failure."""
    doc = {**DOCUMENTS[0], "a": Nested(1, depth, table)}
    with pytest.raises(ParameterError) as refusal:
        from_text(dumps(doc), FILE)
    message = str(refusal.value)
    assert len(message.splitlines()) == 1 and message.startswith(f"{FILE}: ") and "nested" in message, message
