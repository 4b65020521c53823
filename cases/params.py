"""The one validated path for parameter overrides (``--set KEY=VALUE``).

Every failure raises :class:`ParameterError` with one line that names the key and the allowed
range; the command line turns it into exit status 2.

Every number has finite bounds: a valid set of parameters must give finite results, and
extremes such as dt = 1e-300 (1 / dt^2 overflows) or E = 1e300 do not. The bounds are wide
enough for any engineering unit system (the dome is in psi, the rest in SI).
"""

from __future__ import annotations

import ast
import math
import re
from dataclasses import dataclass


class ParameterError(ValueError):
    """A user mistake in a case name, a key or a value."""


def one_line(text) -> str:
    """``text`` with its whitespace runs (line breaks too) made single spaces."""
    return " ".join(str(text).split())


def failure(exc: BaseException) -> str:
    """One line naming an exception: its type, and its message where it has one."""
    return one_line(f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__)


#: largest |stress| or modulus (E, tau_s, q), in the case's units
MAX_STRESS = 1e15
#: smallest modulus (E, tau_s), in the case's units
MIN_MODULUS = 1e-6
#: most time steps one run may take (t_end / dt)
MAX_STEPS = 1_000_000


class UnsupportedCase(ValueError):
    """A solver cannot run a case as it is set up (a clear, user-facing message).

    Both solvers raise it (or a subclass), so the command line can tell it from a bug.
    """


class ToolMissing(UnsupportedCase):
    """An optional external program a solver runs (CalculiX's ``ccx``) is not installed."""


def newmark_only(case, solver: str) -> None:
    """Refuse (:class:`UnsupportedCase`) a case whose ``time_scheme`` is not Newmark's: an
    SMFEM option that ``solver``, with its own time integration, would otherwise ignore."""
    scheme = case.params.get("time_scheme", "newmark")
    if scheme != "newmark":
        raise UnsupportedCase(f"{solver}: time_scheme={scheme} is SMFEM's option; this solver integrates in time "
                              "its own way: leave time_scheme unset")


@dataclass(frozen=True)
class Spec:
    """Allowed values of one parameter: type, bounds (inclusive unless ``open_*``), choices."""

    type: type
    lo: float | None = None
    hi: float | None = None
    open_lo: bool = False
    open_hi: bool = False
    choices: tuple | None = None
    help: str = ""

    def describe(self) -> str:
        if self.choices is not None:
            return "one of " + ", ".join(map(str, self.choices))
        if self.type is bool:
            return "true or false"
        lo = "-inf" if self.lo is None else f"{self.lo:g}"
        hi = "inf" if self.hi is None else f"{self.hi:g}"
        left = "(" if self.open_lo or self.lo is None else "["
        right = ")" if self.open_hi or self.hi is None else "]"
        kind = "an integer" if self.type is int else "a finite number"
        return f"{kind} in {left}{lo}, {hi}{right}"

    def check(self, key: str, value):
        """Return ``value`` converted to the spec's type, or raise ParameterError."""
        bad = f"{key}={value!r} is out of range: {key} must be {self.describe()}"
        if self.type is str:
            if not isinstance(value, str) or value not in (self.choices or ()):
                raise ParameterError(bad)
            return value
        if self.type is bool:
            if isinstance(value, str) and value.lower() in ("true", "false"):
                value = value.lower() == "true"
            if not isinstance(value, bool):
                raise ParameterError(bad)
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParameterError(bad)
        if self.type is int:
            if isinstance(value, float) and not (math.isfinite(value) and value.is_integer()):
                raise ParameterError(bad)
            value = int(value)
        else:
            try:
                value = float(value)
            except OverflowError:  # an integer literal beyond the float range
                raise ParameterError(bad) from None
            if not math.isfinite(value):
                raise ParameterError(bad)
        if self.choices is not None and value not in self.choices:
            raise ParameterError(bad)
        if self.lo is not None and (value < self.lo or (self.open_lo and value == self.lo)):
            raise ParameterError(bad)
        if self.hi is not None and (value > self.hi or (self.open_hi and value == self.hi)):
            raise ParameterError(bad)
        return value


#: keys every case accepts (docs/contract.md), plus ``dim`` for the reference solver
COMMON = {
    "dt": Spec(float, 1e-12, 1e3, help="time step, s"),
    "t_end": Spec(float, 1e-12, 1e6, help="end of the time window, s"),
    "refine": Spec(int, 1, 64, help="multiplies the paper mesh's element counts"),
    "harmonics": Spec(int, 1, 2000, help="number of Fourier terms kept"),
    # the space companion of an error estimate at refine 1 (smfem.runs.estimate): halves the paper mesh
    "coarsen": Spec(int, 1, 16, help="divides the mesh's element counts (each segment keeps at least one element)"),
    "E": Spec(float, MIN_MODULUS, MAX_STRESS, help="Young's modulus"),
    # nu -> 1/2 or -1 leaves double precision: lambda / mu = 2 nu / (1 - 2 nu) is 5e4 at the bound
    "nu": Spec(float, -0.9999, 0.49999, help="Poisson's ratio"),
    "rho": Spec(float, 1e-12, 1e6, help="density"),
    "tau_s": Spec(float, MIN_MODULUS, MAX_STRESS, help="yield stress in pure shear"),
    "plastic": Spec(bool, help="elasto-plastic variant"),
    # a relative change below 1e-14 is round-off: such a tolerance could never be met
    "tol": Spec(float, 1e-14, 1.0, open_hi=True, help="iteration tolerance"),
    "dim": Spec(int, choices=(2, 3), help="reference FEM: 2 (plane strain/axisymmetric) or 3"),
    # absent from every scene's defaults: a run that does not set it keeps its keys (truths, cache)
    "element": Spec(str, choices=("moment4", "quad9"),
                    help="SMFEM's section element: the paper's moment-scheme quadrilateral (the default) or the "
                         "9-node quadratic (smfem/quad9.py)"),
    # the 3D reference only, absent from every scene's defaults as element is: a 3D model of a
    # section with thousands of elements that fits in memory (the flywheel: 64 round would be 1.3
    # million unknowns, past 24 GB to assemble)
    "theta_elements": Spec(int, 4, 4096, help="reference FEM 3D: elements round a ring (default 64 x refine); "
                                             "break points (load patches, cut-outs, probes) add nodes"),
    # the 3D reference only, absent from every scene's defaults as element is: the half of a ring
    # that a 3D analyst would mesh when the loads and the material are mirror-symmetric
    "mirror": Spec(bool, help="reference FEM 3D on a ring symmetric about theta = 0: the half 0 <= theta <= pi, "
                              "u_theta = 0 on the mirror planes (theta_elements still counts round the whole)"),
    # SMFEM's linear runs only, absent from every scene's defaults as element is
    "time_scheme": Spec(str, choices=("newmark", "gauss"),
                        help="SMFEM's time integration of an elastic run without contact: Newmark's average "
                             "acceleration (the paper's, the default) or the 2-stage Gauss-Legendre method "
                             "(order 4, smfem/gauss.py)"),
}

#: the keys of a scene of bodies in contact: the pairs' friction and SMFEM's layer between them
PAIR_SPECS = {
    "friction": Spec(float, 0.0, 10.0, help="Coulomb friction coefficient between the bodies' faces"),
    "layer_thickness": Spec(float, 1e-9, 1e-2, help="SMFEM contact layer thickness, m"),
    "layer_stiffness": Spec(float, 1e-3, 1e6, help="SMFEM contact layer Young's modulus, multiple of E"),
}


#: a bare word ``--set`` takes as a choice (``element=quad9``)
WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_-]*")


def excerpt(text: str, most: int = 60) -> str:
    """``text`` quoted, cut to ``most`` characters (an expression or a value may run to thousands)."""
    return repr(text) if len(text) <= most else f"{text[:most]!r}... ({len(text)} characters)"


def parse_value(key: str, text: str):
    """Parse the VALUE of ``--set KEY=VALUE`` as a Python literal (``1e-5``, ``true``, ``40``)."""
    if text.lower() in ("true", "false"):
        return text.lower() == "true"
    if text.lower() in ("nan", "inf", "-inf", "+inf"):
        return float(text)
    try:
        return ast.literal_eval(text)
    except (ValueError, TypeError, SyntaxError, MemoryError, RecursionError):
        if WORD.fullmatch(text):  # a choice such as element=quad9; the key's spec checks it
            return text
        raise ParameterError(f"{key}={excerpt(text)} is not a value: write a number, true/false or a choice") from None


def parse_option(key: str, text: str):
    """The VALUE of ``--set KEY=VALUE`` for a solver's own option: as :func:`parse_value`, or the
    text itself (a word such as ``iteration_matrix=sor``, or a mistake the option's spec
    refuses)."""
    try:
        return parse_value(key, text)
    except ParameterError:
        return text


def parse_sets(items) -> dict:
    """Parse a list of ``KEY=VALUE`` strings into a dict (last one wins)."""
    out = {}
    for item in items or ():
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key or not text.strip():
            raise ParameterError(f"malformed --set {item!r}: expected KEY=VALUE, e.g. --set dt=1e-5")
        out[key] = parse_value(key, text.strip())
    return out


def validate(specs: dict[str, Spec], defaults: dict, overrides: dict, case_name: str) -> dict:
    """Merge ``overrides`` into ``defaults`` after checking every key and value."""
    params = dict(defaults)
    for key, value in overrides.items():
        if key not in specs:
            raise ParameterError(
                f"unknown key {key!r} for case {case_name!r}: allowed keys are {', '.join(sorted(specs))}"
            )
        params[key] = specs[key].check(key, value)
    if params["dt"] > params["t_end"]:
        raise ParameterError(f"dt={params['dt']:g} is out of range: dt must not exceed t_end={params['t_end']:g}")
    if params["t_end"] / params["dt"] > MAX_STEPS + 0.5:
        raise ParameterError(
            f"t_end={params['t_end']:g} and dt={params['dt']:g} are out of range: t_end / dt must be at most "
            f"{MAX_STEPS} time steps"
        )
    return params


def out_of_range(spec: Spec) -> list[str]:
    """Values (as ``--set`` text) that ``spec`` must refuse: past each bound, the open bounds
    themselves, the non-finite floats, wrong types. The bad-input tests and the report's
    stability section sweep them over every key."""
    if spec.type is bool:
        return ["3", "maybe", "1.0"]
    if spec.type is str:
        return ["1", "x", "true"]
    if spec.choices is not None:
        return [repr(max(spec.choices) + 1), "x"]
    bad = ["nan", "inf", "-inf", "'x'", "(1, 2)"]
    if spec.lo is not None:
        bad.append(repr(spec.lo - max(1.0, abs(spec.lo))))
        if spec.open_lo:
            bad.append(repr(spec.lo))
    if spec.hi is not None:
        bad.append(repr(spec.hi + max(1.0, abs(spec.hi))))
        if spec.open_hi:
            bad.append(repr(spec.hi))
    if spec.type is int:
        bad += ["1.5", "true"]
    return bad
