"""Expressions of a scene file are read from a whitelist, never run (cases/expressions.py, issue
36): the same sympy expression as sympify gave for everything the project writes, a one-line
refusal of anything else, cheap limits against hostile input, and through the command line an
injected command that never runs."""

from __future__ import annotations

import builtins
import json
import warnings
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from cases import manufactured as mf
from cases import verification
from cases.expressions import (MAX_BITS, MAX_DEPTH, MAX_LENGTH, ExpressionError, VariableError, parse)
from cases.geometry import PRISM, RING
from smfem.cli import main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
#: what sympify read before: the real symbols by name, the rest of its namespace sympy's
TRUSTED = {str(v): v for v in mf.VARIABLES}
#: expressions written by hand in tests/ and docs/ (grep pattern, time), and sympy's spellings
#: the whitelist keeps: ^, abs and Abs, log with a base, Heaviside with H0, a long mantissa
WRITTEN = ["0", "1", "7", "t", "x1", "x3", "sin(x3)", "cos(x3)", "-7.8e4", "-9.81 * 7800",
           "-7.8e4 * (1 + 0.2 * cos(2 * x3))", "x1 * cos(pi * x3)", "1 + 0.3*cos(2*x3) * t", "1 - cos(3.0*t)",
           "9.0*cos(3.0*t)", "t**2", "t^2", "2^3^2", "-x1**2", "(-x1)**2", "2**-1", "- 3", "+x1", "--x1",
           "x1/2/x2", "x1 - x2 - x3", "E**x1", "exp(-0.5*x1)*sqrt(x2)", "abs(x1 - 1) + Abs(-x2)", "log(x1, 10)",
           "log(8, 2)", "Heaviside(x1 - 0.5)", "Heaviside(x1, 1)", "tan(x1) + tanh(x2) + sinh(x3) + cosh(t)",
           "atan(x1/x2)", "1.23456789012345678901234*x1", "1e-5 + 1E5 + .5 + 5. + 1_000.5e1_0 + 1_000",
           "0.300000000000000*x1", " x1 + 1 ", "(x1 +\n x2)", "sqrt(8) + 8**(1/3) + (1/3)**(1/2)",
           "2**1023", "cos(pi*10**300/3)", "x1**(10**100)", "pi*E"]


def manufactured_texts() -> set[str]:
    """Every expression string of the manufactured scenes: both bodies, with and without a free
    top, both time functions, the material variations the verification and its tests use (none
    and a = 0.3); the forces and the exact motion."""
    texts = set()
    for body in (PRISM, RING):
        for free_top in (False, True):
            for time in ("cos", "quadratic"):
                for a in (0.0, 0.3):
                    case = verification.build(body, {"free_top": free_top, "time": time, "a": a})
                    for term in case.forces + (case.exact,):
                        texts |= set(term.pattern) | {term.time}
    return texts


@pytest.fixture(scope="module")
def texts() -> list[str]:
    return sorted(manufactured_texts()) + WRITTEN


def test_the_whitelist_builds_what_sympify_built(texts):
    """Bit-identical runs: the same expression, printed alike, so lambdify writes the same code.
    Mostly sympy's cache hands both the very same object, printed alike without printing it
    (its srepr of the long ones: 2 s)."""
    assert len(texts) > 100 and max(map(len, texts)) > 5000
    for text in texts:
        ours, theirs = parse(text), sp.sympify(text, locals=TRUSTED)
        assert ours == theirs and (ours is theirs or sp.srepr(ours) == sp.srepr(theirs)), text


def test_nothing_is_evaluated_as_code(texts, monkeypatch):
    import sympy.parsing.sympy_parser as sympy_parser

    def refuse(*args, **kwargs):
        raise AssertionError("text evaluated as code")

    for target, name in ((builtins, "eval"), (builtins, "exec"), (sympy_parser, "parse_expr"), (sp, "sympify")):
        monkeypatch.setattr(target, name, refuse)
    assert all(parse(text) is not None for text in texts[-len(WRITTEN):] + texts[:5])


@pytest.mark.parametrize("text, needle", [
    ("__import__('os').system('touch pwned') or 0", "and/or is not allowed"),
    ("__import__('os').system('touch pwned')", "attribute access"),
    ("__import__('os')", "'__import__' is not a known name: use x1, x2, x3, t, pi, E and the functions sin, cos"),
    ("x1.__class__", "attribute access"),
    ("().__class__.__bases__[0].__subclasses__()", "attribute access"),
    ("x1[0]", "indexing"),
    ("'x1'", "a string is not allowed"),
    ("b'x1'", "bytes are not allowed"),
    ("f'{x1}'", "a string is not allowed"),
    ("lambda: 0", "lambda is not allowed"),
    ("[x for x in (1, 2)]", "a comprehension is not allowed"),
    ("sin(x=1)", "keyword arguments are not allowed"),
    ("sin(*[x1])", "starred"),
    ("sin(**{'x': 1})", "keyword arguments are not allowed"),
    ("x1 < 2", "a comparison is not allowed"),
    ("x1 if x2 else 0", "if/else is not allowed"),
    ("(y := 1)", "assignment (:=) is not allowed"),
    ("x1 // 2", "the operator // is not allowed"),
    ("~x1", "the operator ~ is not allowed"),
    ("1j", "imaginary numbers are not allowed"),
    ("True", "True is not allowed"),
    ("None", "None is not allowed"),
    ("(1, 2)", "a tuple is not allowed"),
    ("globals()", "'globals' is not a known name"),
    ("eval('1')", "'eval' is not a known name"),
    ("getattr(x1, 'func')", "'getattr' is not a known name"),
    ("y + 1", "'y' is not a known name"),
    ("I", "'I' is not a known name"),
    ("sin", "sin is a function: call it"),
    ("x1(2)", "x1 is not a function"),
    ("sin(x1)(2)", "only the functions sin, cos"),
    ("sin(x1, x2)", "sin takes 1 argument, not 2"),
    ("Heaviside(x1, 1, 2)", "Heaviside takes 1 or 2 arguments, not 3"),
    ("import os", "invalid syntax"),
    ("1 +* 2", "invalid syntax"),
    ("", "empty"),
    ("x1\x00", "null bytes"),
    ("1/0", "not a finite real number"),
    ("sqrt(-1)", "not a finite real number"),
    ("log(0)", "not a finite real number"),
    ("2.0**2000", "not a finite real number"),
])
def test_anything_else_is_refused_in_one_line(text, needle):
    with pytest.raises(ExpressionError) as refusal:
        parse(text)
    message = str(refusal.value)
    assert needle in message and len(message.splitlines()) == 1, message


@pytest.mark.parametrize("text, needle", [
    # sympy would compute these exactly: minutes, or memory without end
    ("9**9**9**9", "a power too large"),
    ("10**10**10**10", "a power too large"),
    ("2**1024", "a power too large"),
    ("(1/3)**700", "a power too large"),
    ("sqrt(2)**(10**100)", "a power too large"),
    ("(2*x1)**(10**100)", "a power too large"),
    ("2**x1 * 2**(10**100 - x1)", "a power too large"),  # equal bases add their exponents
    ("exp(10**100*log(2))", "a power too large"),  # exp(c log b) is b**c
    ("E**(10**100*log(2))", "a power too large"),
    ("exp(2)**(log(3)*10**100)", "a power too large"),
    ("sqrt(2**1000 + 1)", "a root of a number of more than 256 bits"),  # perfect-power search
    ("(2**1023)*(2**1023)", f"would pass {MAX_BITS} bits"),
    ("9" * 400, f"would pass {MAX_BITS} bits"),
    ("1e999999", "beyond a float's range"),  # sympy's Float of it takes a minute
    ("0.0e-99999999", "beyond a float's range"),
    ("1e-400", "beyond a float's range"),
    ("x1" + "+x1" * (MAX_LENGTH // 3), f"longer than {MAX_LENGTH} characters"),
    ("x1" + "+x1" * (MAX_DEPTH + 1), f"nested more than {MAX_DEPTH} levels deep"),
    ("-" * 3000 + "x1", "nested"),
    ("(" * 500 + "x1" + ")" * 500, "too many nested parentheses"),
    ("sin(" * 300 + "x1" + ")" * 300, "too many nested parentheses"),
    ("sin(" * (MAX_DEPTH + 5) + "x1" + ")" * (MAX_DEPTH + 5), f"nested more than {MAX_DEPTH} levels deep"),
])
def test_what_would_exhaust_time_or_memory_is_refused(text, needle):
    with pytest.raises(ExpressionError, match=needle.replace("(", r"\(")):
        parse(text)


def test_pythons_parser_says_nothing_on_stderr():
    """Its "invalid decimal literal" would be a second line under the refusal."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ExpressionError, match="if/else"):
            parse("1if x1 else 0")


def test_each_key_allows_its_own_variables():
    assert parse("x1 * sin(x3)", ("x1", "x2", "x3")).free_symbols == {mf.X1, mf.X3}
    with pytest.raises(VariableError) as refusal:
        parse("x1 + t", ("x1", "x2", "x3"))
    assert refusal.value.name == "t" and "use x1, x2, x3, pi, E" in str(refusal.value)
    with pytest.raises(VariableError, match="use t, pi, E"):
        parse("1 - cos(x1)", ("t",))


def test_numpy_evaluates_whatever_is_accepted():
    with pytest.raises(ExpressionError, match="numpy cannot evaluate it"):
        mf.numeric("sin(10**300) * x1")  # an integer past int64 inside a ufunc
    with pytest.raises(ExpressionError, match="complex"):
        mf.numeric("(-1)**(1/3) * x1")  # complex, though no I appears in it
    assert np.all(mf.numeric("x1**(10**100)")(np.array([0.5, 1.0]), 0.0, 0.0, 0.0) == [0.0, 1.0])


#: a scene with a body force and a traction: the notched strip's file with two forces added
FORCES = """
[[body_force]]
pattern = ["0", "-9.81 * 7800", "0"]
time = "1"

[[traction]]
edge = "top"
pattern = ["0", "-1e6 * sin(pi * x3 / 0.3)", "0"]
time = "t / 3.2e-4"
"""

#: commands hidden in expressions, and other ways out; {marker} is a file they would create
PAYLOADS = [
    "__import__('os').system('touch {marker}') or 0",
    "__import__('os').system('touch {marker}')",
    "__import__('pathlib').Path('{marker}').touch()",
    "open('{marker}', 'w').write('x')",
    "exec(\"open('{marker}', 'w')\")",
    "eval(\"__import__('os').system('touch {marker}')\")",
    "x1.__class__",
    "().__class__.__bases__[0].__subclasses__()",
    "globals()",
    "getattr(x1, '__class__')",
    "lambda: 0",
    "'{marker}'",
    "x1[0]",
    "sin(x=1)",
    "import os; os.system('touch {marker}')",
    "[__import__('os').system('touch {marker}') for _ in (1,)]",
    "x1 if __import__('os').system('touch {marker}') else 0",
    "Symbol('x1')",
    "x1" + "+x1" * (MAX_LENGTH // 3),
    "(" * 500 + "x1" + ")" * 500,
    "-" * 3000 + "x1",
    "sin(" * 300 + "x1" + ")" * 300,
    "9**9**9**9",
    "exp(10**100*log(2))",
]
#: where an expression goes: the key's place in the file and in the message
SLOTS = [("body_force", "pattern", 1), ("traction", "pattern", 1), ("traction", "time", None)]


def scene_with(slot, expression: str) -> str:
    """The notched strip with its forces, one expression replaced."""
    table, key, index = slot
    start = FORCES.index(f"[[{table}]]")
    line_start = FORCES.index(f"{key} = ", start)
    line_end = FORCES.index("\n", line_start)
    if index is None:
        line = f"{key} = {json.dumps(expression)}"
    else:
        values = json.loads(FORCES[line_start + len(key) + 3:line_end])
        values[index] = expression
        line = f"{key} = [{', '.join(json.dumps(v) for v in values)}]"
    return (EXAMPLES / "notched_strip.toml").read_text() + FORCES[:line_start] + line + FORCES[line_end:]


def test_the_scene_with_forces_runs(tmp_path, capsys):
    scene, out = tmp_path / "strip.toml", tmp_path / "out"
    scene.write_text((EXAMPLES / "notched_strip.toml").read_text() + FORCES)
    args = ["run", str(scene), "--estimate", "off", "--no-fields", "--quiet", "--out", str(out)]
    assert main(args + ["--set", "t_end=6.4e-6", "--set", "harmonics=8"]) == 0, capsys.readouterr().err
    assert (out / "history.csv").exists()


@pytest.mark.parametrize("slot", SLOTS, ids=lambda s: f"{s[0]}.{s[1]}")
@pytest.mark.parametrize("payload", PAYLOADS, ids=range(len(PAYLOADS)))
def test_an_injected_expression_never_runs(tmp_path, capsys, slot, payload):
    """Exit 2, one line naming the file and the key, nothing written, no marker file."""
    marker, scene, out = tmp_path / "MARKER", tmp_path / "scene.toml", tmp_path / "out"
    scene.write_text(scene_with(slot, payload.format(marker=marker)))
    code = main(["run", str(scene), "--estimate", "off", "--no-fields", "--quiet", "--out", str(out)])
    err = capsys.readouterr().err.strip()
    table, key, _ = slot
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    assert err.startswith(f"smfem: error: {scene}: {table}[1].{key}: "), err
    assert not out.exists() and not marker.exists()


@pytest.mark.parametrize("slot, expression, needle", [
    (SLOTS[0], "exp(1e5*x2)", "is not finite inside the body (at x1 = "),
    (SLOTS[1], "1/(x2 - x2)", "not a finite real number"),
    (SLOTS[1], "x2 * exp(1e5*x2)", "is not finite inside the body"),
    (SLOTS[2], "1/t", "cannot be evaluated at t = 0 (ZeroDivisionError"),
    (SLOTS[2], "(t - 1)**0.5", "cannot be evaluated at t = 0 (TypeError"),
    (SLOTS[2], "exp(1e7*t)", "is not finite at t = "),
])
def test_a_force_no_solver_could_apply_is_refused_before_any_run(tmp_path, capsys, slot, expression, needle):
    """Found reviewing the parser: exp(1000*x1) ran into a traceback in SMFEM's assembly, a time
    factor 1/t into a ZeroDivisionError at the first step. Each is refused as the file is read."""
    scene, out = tmp_path / "scene.toml", tmp_path / "out"
    scene.write_text(scene_with(slot, expression))
    code = main(["run", str(scene), "--estimate", "off", "--no-fields", "--quiet", "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and needle in err, err
    assert err.startswith(f"smfem: error: {scene}: {slot[0]}[1].{slot[1]}: ") and not out.exists()
