"""Expressions of a scene, read from a whitelist: nothing in the text runs as code.

A scene file's body forces and tractions are expressions of the coordinates and time
(docs/scenes.md, "Scenes from a file"). ``sympy.sympify`` evaluates its text as Python (a
pattern ``"__import__('os').system(...) or 0"`` runs a command), and scene files are shared, so
:func:`parse` reads the text with :mod:`ast` and builds the sympy expression itself from listed
pieces: numbers, the variables, ``pi``, ``E``, ``+ - * / **`` (or ``^``), unary ``-`` and
``+``, parentheses, and calls of :data:`FUNCTIONS`. Whatever it accepts, it builds as sympify's
own parser does (an integer literal is an ``Integer``, a decimal one the ``Float`` of its own
digits, the operators are sympy's), so the expression, the code lambdify writes for it and the
runs are the same as before.

Limits keep a hostile text cheap: its length and depth, floats within a float's range, and the
exact numbers sympy would work out (``9**9**9**9``, the square root of a huge integer,
``exp(10**100*log(2))``) at most :data:`MAX_BITS` bits.
"""

from __future__ import annotations

import ast
import math
import operator
import re
import warnings

import sympy as sp

from .params import failure, one_line

X1, X2, X3, T = sp.symbols("x1 x2 x3 t", real=True)
#: the names an expression may use: the body's coordinates and time
VARIABLES = (X1, X2, X3, T)
NAMES = tuple(str(v) for v in VARIABLES)
CONSTANTS = {"pi": sp.pi, "E": sp.E}
#: name -> (function, fewest and most arguments); ``abs`` is Python's, as in sympify
FUNCTIONS = {"sin": (sp.sin, 1, 1), "cos": (sp.cos, 1, 1), "tan": (sp.tan, 1, 1), "exp": (sp.exp, 1, 1),
             "log": (sp.log, 1, 2), "sqrt": (sp.sqrt, 1, 1), "abs": (abs, 1, 1), "Abs": (sp.Abs, 1, 1),
             "tanh": (sp.tanh, 1, 1), "sinh": (sp.sinh, 1, 1), "cosh": (sp.cosh, 1, 1), "atan": (sp.atan, 1, 1),
             "Heaviside": (sp.Heaviside, 1, 2)}
OPERATORS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
             ast.Pow: operator.pow}
SIGNS = {ast.USub: operator.neg, ast.UAdd: operator.pos}
#: longest text (the manufactured ring's body forces run to 5.7k characters)
MAX_LENGTH = 10_000
#: deepest syntax tree (the manufactured forces: 31)
MAX_DEPTH = 100
#: largest exact number, in bits: within a float's range, where lambdify's code takes it
MAX_BITS = 1023
#: largest exact number sympy may take a root of: it looks for perfect powers and small
#: factors, a cost that grows as the cube of the bits (5 s at 13000 bits)
ROOT_BITS = 256
#: a float literal's decimal exponent; sympy's Float of '0.0e-99999999' takes minutes
MAX_EXPONENT = 400
EXPONENT = re.compile(r"[eE]([+-]?[0-9_]+)$")
LEAVES = (ast.Load, ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.USub, ast.UAdd)
#: what a refused piece of syntax is called in a message
REFUSED = {ast.Attribute: "attribute access (.name)", ast.Subscript: "indexing ([...])", ast.Lambda: "lambda",
           ast.ListComp: "a comprehension", ast.SetComp: "a comprehension", ast.DictComp: "a comprehension",
           ast.GeneratorExp: "a comprehension", ast.Compare: "a comparison", ast.BoolOp: "and/or",
           ast.IfExp: "if/else", ast.NamedExpr: "assignment (:=)", ast.JoinedStr: "a string",
           ast.Tuple: "a tuple", ast.List: "a list", ast.Set: "a set", ast.Dict: "a dict",
           ast.Starred: "a starred argument (*)", ast.Slice: "a slice", ast.Await: "await",
           ast.Yield: "yield", ast.YieldFrom: "yield"}
OPERATOR_SIGNS = {ast.FloorDiv: "//", ast.Mod: "%", ast.MatMult: "@", ast.LShift: "<<", ast.RShift: ">>",
                  ast.BitOr: "|", ast.BitXor: "^", ast.BitAnd: "&", ast.Not: "not", ast.Invert: "~"}
NOT_FINITE = (sp.S.ImaginaryUnit, sp.S.ComplexInfinity, sp.S.NaN, sp.S.Infinity, sp.S.NegativeInfinity)
LARGEST_FLOAT = sp.Float(1.7976931348623157e308)


class ExpressionError(ValueError):
    """An expression that is not allowed, in one line that says what."""


class VariableError(ExpressionError):
    """A variable the expression may not use here (``t`` in a pattern): ``name``."""

    def __init__(self, name: str, message: str):
        super().__init__(message)
        self.name = name


def parse(text: str, variables: tuple[str, ...] = NAMES) -> sp.Expr:
    """The sympy expression of ``text``: numbers, ``variables`` (some of ``x1, x2, x3, t``),
    ``pi``, ``E``, ``+ - * / **`` (or ``^``) and calls of :data:`FUNCTIONS`; the same expression
    as ``sympy.sympify(text)``, which it never calls. Anything else is an :class:`ExpressionError`."""
    if not isinstance(text, str):
        raise ExpressionError(f"{type(text).__name__} is not an expression: write it as a string")
    # as sympify: newlines dropped, ^ is a power
    text = text.replace("\n", "").strip()
    if not text:
        raise ExpressionError("empty: write an expression, e.g. 0")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"longer than {MAX_LENGTH} characters")
    text = text.replace("^", "**")
    try:
        with warnings.catch_warnings():  # "invalid decimal literal" and the like: not the user's stderr
            warnings.simplefilter("ignore")
            tree = ast.parse(text, mode="eval")
    except SyntaxError as exc:
        raise ExpressionError(one_line(exc.msg)) from None
    except ValueError as exc:  # null bytes (Python 3.11)
        raise ExpressionError(one_line(exc)) from None
    except (RecursionError, MemoryError):
        raise ExpressionError(f"nested too deeply for Python's parser (here at most {MAX_DEPTH} levels)") from None
    builder = _Builder(text, variables)
    builder.check(tree)
    try:
        return builder.build(tree.body)
    except ExpressionError:
        raise
    except (ArithmeticError, TypeError, ValueError, RecursionError, MemoryError) as exc:
        raise ExpressionError(f"sympy cannot build it ({failure(exc)})") from None


class _Builder:
    """Checks the syntax tree of one text against the whitelist, then builds it bottom up,
    weighing the exact numbers of every piece before sympy may raise them to a power."""

    def __init__(self, text: str, variables: tuple[str, ...]):
        self.lines = text.encode().splitlines()  # as ast counts: lines of UTF-8 bytes
        self.variables = {name: VARIABLES[NAMES.index(name)] for name in variables}
        self.weights: dict = {}
        self.known = (f"use {', '.join(variables)}, pi, E and the functions "
                      f"{', '.join(FUNCTIONS)} (+ - * / ** and parentheses)")

    def check(self, tree: ast.Expression) -> None:
        """Every node of ``tree`` listed, every name known, every call of a listed function by
        name with positional arguments of the right number; no deeper than :data:`MAX_DEPTH`.
        Outer nodes first, so the message names the outermost thing refused."""
        stack = [(tree.body, 1)]
        while stack:
            node, depth = stack.pop()
            if depth > MAX_DEPTH:
                raise ExpressionError(f"nested more than {MAX_DEPTH} levels deep")
            children = list(ast.iter_child_nodes(node))
            if isinstance(node, ast.Call):
                self.check_call(node)
                children = node.args
            elif isinstance(node, ast.Name):
                self.name(node.id)
            elif isinstance(node, ast.Constant):
                self.check_constant(node.value)
            elif isinstance(node, (ast.BinOp, ast.UnaryOp)):
                if type(node.op) not in OPERATORS and type(node.op) not in SIGNS:
                    raise ExpressionError(f"the operator {OPERATOR_SIGNS.get(type(node.op), '?')} is not allowed: "
                                          "use + - * / ** (or ^)")
            elif not isinstance(node, LEAVES):
                raise ExpressionError(f"{REFUSED.get(type(node), type(node).__name__)} is not allowed")
            stack.extend((child, depth + 1) for child in children)

    def check_call(self, node: ast.Call) -> None:
        if not isinstance(node.func, ast.Name):
            what = REFUSED.get(type(node.func))
            raise ExpressionError(f"{what} is not allowed" if what else
                                  f"only the functions {', '.join(FUNCTIONS)} can be called, by name")
        name = node.func.id
        if name not in FUNCTIONS:
            self.name(name)  # an unknown name, or a variable
            raise ExpressionError(f"{name} is not a function: the functions are {', '.join(FUNCTIONS)}")
        if node.keywords:
            raise ExpressionError(f"{name}(...): keyword arguments are not allowed")
        _, fewest, most = FUNCTIONS[name]
        if not fewest <= len(node.args) <= most:
            count = f"{fewest}" if fewest == most else f"{fewest} or {most}"
            raise ExpressionError(f"{name} takes {count} argument{'s' if most > 1 else ''}, not {len(node.args)}")

    @staticmethod
    def check_constant(value) -> None:
        if isinstance(value, str):
            raise ExpressionError("a string is not allowed")
        if isinstance(value, bytes):
            raise ExpressionError("bytes are not allowed")
        if isinstance(value, complex):
            raise ExpressionError("imaginary numbers are not allowed")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ExpressionError(f"{value!r} is not allowed: write a number")

    def name(self, name: str) -> sp.Basic:
        if name in self.variables:
            return self.variables[name]
        if name in NAMES:
            raise VariableError(name, f"{name} is not a variable here: {self.known}")
        if name in CONSTANTS:
            return CONSTANTS[name]
        if name in FUNCTIONS:
            raise ExpressionError(f"{name} is a function: call it, e.g. {name}(x1)")
        raise ExpressionError(f"{name!r} is not a known name: {self.known}")

    def build(self, node: ast.expr) -> sp.Expr:
        """The sympy expression of a checked ``node`` (recursion no deeper than :data:`MAX_DEPTH`)."""
        if isinstance(node, ast.Constant):
            value = self.number(node)
        elif isinstance(node, ast.Name):
            value = self.name(node.id)
        elif isinstance(node, ast.UnaryOp):
            value = SIGNS[type(node.op)](self.build(node.operand))
        elif isinstance(node, ast.BinOp):
            left, right = self.build(node.left), self.build(node.right)
            if isinstance(node.op, ast.Pow):
                self.check_power(left, right)
            value = OPERATORS[type(node.op)](left, right)
        else:
            name = node.func.id
            args = [self.build(a) for a in node.args]
            if name == "sqrt":
                self.check_power(args[0], sp.S.Half)
            elif name == "exp":
                self.check_power(sp.E, args[0])
            value = FUNCTIONS[name][0](*args)
        bits, _, _, _, finite = self.weigh(value)
        if not finite:
            raise ExpressionError("not a finite real number (a division by zero, log(0), the root of a negative "
                                  "number, a float overflow, ...)")
        if bits > MAX_BITS:
            raise ExpressionError(f"a number in it would pass {MAX_BITS} bits (about 1e308)")
        return value

    def number(self, node: ast.Constant) -> sp.Number:
        """As sympify reads a literal: an ``Integer``, or the ``Float`` of the literal's own digits."""
        if isinstance(node.value, int):
            return sp.Integer(node.value)
        # ast.get_source_segment splits the whole text at every call
        digits = self.lines[node.lineno - 1][node.col_offset:node.end_col_offset].decode()
        exponent = EXPONENT.search(digits)
        value = float(digits)
        underflow = value == 0 and any(c in "123456789" for c in digits[:exponent.start() if exponent else None])
        if (exponent and abs(int(exponent.group(1))) > MAX_EXPONENT) or not math.isfinite(value) or underflow:
            raise ExpressionError(f"{digits} is beyond a float's range (about 1e-308 to 1e308)")
        return sp.Float(digits)

    def check_power(self, base: sp.Expr, exponent: sp.Expr) -> None:
        """Refuse ``base ** exponent`` (``exp(exponent)`` for base E, ``sqrt``) where sympy would
        work out an exact number past :data:`MAX_BITS` bits, or a root of one past
        :data:`ROOT_BITS`: it raises exact numbers to rational powers at once, adds the
        exponents of equal bases (``2**x1 * 2**(10**100 - x1)``), and turns ``exp(c log(b))``
        into ``b**c`` (so with a log, the exponent's numbers may become bases). Conservative: it
        weighs every exact number in the pieces, where sympy might use only some."""
        bits, _, _, base_log, _ = self.weigh(base)
        exponent_bits, magnitude, fraction, exponent_log, _ = self.weigh(exponent)
        if base_log or exponent_log:
            bits = max(bits, exponent_bits)
        if bits and magnitude > MAX_BITS / bits:
            raise ExpressionError(f"a power too large: it would pass {MAX_BITS} bits (about 1e308)")
        if bits > ROOT_BITS and fraction:
            raise ExpressionError(f"a root of a number of more than {ROOT_BITS} bits")

    def weigh(self, expr: sp.Basic) -> tuple[float, int, bool, bool, bool]:
        """``(bits, magnitude, fraction, log, finite)`` of the exact numbers in ``expr``: the
        largest numerator or denominator in bits (log2), the largest magnitude (rounded up),
        whether one is not an integer; whether a log is in it, and whether it is finite and real
        (no I, zoo, nan, oo, or float past a float's range). Each piece is weighed once
        (``weights``), so weighing every new piece costs about what building it did."""
        if expr in self.weights:
            return self.weights[expr]
        if expr.is_Rational:
            p, q = abs(expr.p), expr.q
            weight = (math.log2(max(p, q)) if p else 0.0, -(-p // q), q != 1, False, True)
        elif expr.is_Float:
            weight = (0.0, 0, False, False, bool(abs(expr) <= LARGEST_FLOAT))
        elif any(expr is special for special in NOT_FINITE):
            weight = (0.0, 0, False, False, False)
        else:
            parts = [self.weigh(a) for a in expr.args]
            weight = (max((w[0] for w in parts), default=0.0), max((w[1] for w in parts), default=0),
                      any(w[2] for w in parts), isinstance(expr, sp.log) or any(w[3] for w in parts),
                      all(w[4] for w in parts))
        self.weights[expr] = weight
        return weight
