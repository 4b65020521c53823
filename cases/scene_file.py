"""Scenes from a TOML file: ``smfem run my_scene.toml`` (docs/scenes.md, "Scenes from a file").

A file describes one body of revolution (``body = "ring"``) or prism (``body = "prism"``) with
the pieces of :mod:`cases.geometry`, or several such bodies (``[[bodies]]``, one mapped block
each, assembled by :func:`cases.bodies.assemble`, or the physical surfaces of a gmsh mesh
section that share no node) and the contact pairs between their faces (``[[contact]]``). Its
``[params]`` are checked by the specs of ``--set`` (:data:`cases.params.COMMON` and the
built-in scenes' own keys) and then merged with the overrides by :func:`cases.params.validate`,
the one path of ``--set``. Any number of the scene may be written as the name of a parameter in
quotes (``q = "q"``, ``value = "-v0"``): it then follows ``--set``.

An angle may name a parameter in degrees: ``"patch_deg deg"`` is its value in radians.

Every mistake in a file is a :class:`ParameterError` of one line that names the file and the
key (``scene.toml: section.s.counts: ...``); unknown keys are refused. No solver imports here.
"""

from __future__ import annotations

import hashlib
import math
import re
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path
from types import SimpleNamespace

from . import (dome, flywheel, layered_cylinder, moving_load, notched_cylinder, notched_strip, rod_collision,
               rod_impact, thick_cylinder)
from .bodies import Body, assemble, body_of, check_pairs, check_touching
from .case import Case
from .geometry import (EDGES, PRISM, RING, UNIFORM_SHIFTS, Amplitude, Axis, ContactPair, Cutout, Force, InitialVelocity,
                       Pressure, Probe, Region, Section, Support, Wall)
from .material import Material
from .params import COMMON, MAX_STRESS, ParameterError, Spec, UnsupportedCase, excerpt, failure, validate


def _scene_keys() -> dict[str, Spec]:
    """The built-in scenes' own keys (q, contrast, notch_depth, v0, gap, ...) with their ranges."""
    keys: dict[str, Spec] = {}
    for module in (dome, thick_cylinder, notched_cylinder, notched_strip, rod_impact, layered_cylinder, flywheel,
                   moving_load, rod_collision):
        keys.update({k: spec for k, spec in module.SPECS.items() if k not in COMMON and k not in keys})
    return keys


SCENE_KEYS = _scene_keys()

#: [params] keys a file must give; the other common keys default to OPTIONAL
REQUIRED = ("dt", "t_end", "harmonics", "E", "nu", "rho", "tau_s")
#: the deepest nesting of arrays and tables a scene file may have (the file itself counts one,
#: a body's axis breaks five); deeper ones are refused before anything walks them
MAX_DEPTH = 16
OPTIONAL = dict(refine=1, plastic=False, tol=1e-5, dim=2)
#: scene keys the features of the scene read themselves: required with any of them, refused
#: without all of them (SMFEM's contact layer is a wall's and a contact pair's)
BOUND = {"contrast": ("cutout",), "layer_thickness": ("wall", "contact"), "layer_stiffness": ("wall", "contact")}
FEATURES = {"cutout": "[[cutout]]", "wall": "[wall]", "contact": "[[contact]]"}

TOP = ("name", "title", "body", "units", "length", "symmetric", "axisymmetric", "params", "material",
       "section", "bodies", "region", "load", "body_force", "traction", "support", "cutout", "initial_velocity", "wall",
       "contact", "probe", "references")
#: a material's own constants (a region's, a body's); the others are the scene's, [params]
MATERIAL_KEYS = ("E", "nu", "rho", "tau_s", "E_T")
REGION_KEYS = ("name", *MATERIAL_KEYS, "s_range", "t_range")
#: a body of a scene of several: its name, its mapped block as [section] takes it, its material
BODY_KEYS = ("name", "kind", "s", "t", "edges", *MATERIAL_KEYS)
CONTACT_KEYS = ("face", "other", "friction", "interference")
VELOCITY_KEYS = ("component", "value", "region")
PROBE_KEYS = ("name", "kind", "field", "component", "point", "edge", "region")
#: probe kind -> the fields it may record
PROBE_FIELDS = {"point": ("u", "v", "sigma", "peps"), "max": ("peps",), "edge_mean": ("sigma",),
                "body_mean": ("u", "v")}
#: the fastest a load may move along x3 (m/s on a prism, rad/s on a ring)
MAX_SPEED = 1e8
#: most elements in one segment of a section axis (before ``refine``)
MAX_COUNT = 10_000
NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")
WORD = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
TWO_PI = 2 * math.pi
_MISSING = object()


@dataclass(frozen=True)
class Source:
    """What a file scene was read from: the path as given, its text (:func:`cases.rebuild`) and
    the sha256 of each other file it read (a gmsh section), by path."""

    path: str
    text: str
    files: tuple = ()

    @property
    def digest(self) -> str:
        """sha256 of everything the scene was read from: what a run of it depends on besides
        its parameters (the run cache's key)."""
        h = hashlib.sha256(self.text.encode())
        for _, sha in self.files:
            h.update(sha.encode())
        return h.hexdigest()


def load(path, overrides: dict | None = None) -> Case:
    """The scene of TOML file ``path`` with validated ``overrides`` (``--set``)."""
    file = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise ParameterError(f"{file}: cannot read the scene file ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise ParameterError(f"{file}: cannot read the scene file (not UTF-8 text)") from None
    return from_text(text, file, overrides)


def from_text(text: str, file: str, overrides: dict | None = None) -> Case:
    """The scene of TOML ``text`` read from ``file`` (named in every error message)."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(_one_line(f"{file}: not valid TOML: {exc}")) from None
    except RecursionError:  # tomllib reads nested arrays and tables recursively
        raise ParameterError(f"{file}: arrays or tables nested too deeply to read (a scene file nests at most "
                             f"{MAX_DEPTH} levels)") from None
    depth = _depth(doc)
    if depth > MAX_DEPTH:
        raise ParameterError(f"{file}: arrays or tables nested {depth} levels deep (a scene file nests at most "
                             f"{MAX_DEPTH} levels)")
    return _Scene(file, doc).build(overrides or {}, Source(file, text))


def _depth(doc) -> int:
    """How deeply arrays and tables nest in ``doc`` (a value: 0), without recursion."""
    deepest, stack = 0, [(doc, 1)]
    while stack:
        node, level = stack.pop()
        if isinstance(node, (dict, list)):
            deepest = max(deepest, level)
            stack.extend((child, level + 1) for child in (node.values() if isinstance(node, dict) else node))
    return deepest


def _one_line(message: str) -> str:
    """``message`` with every unprintable character escaped: the line breaks Python knows
    (``\\x1e``, ``\\u2028``, ... besides ``\\n``) and the ones that hide text (``\\u202e``)."""
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode() for c in message)



class _Table:
    """One table of the file: typed values, unknown keys refused, numbers that may name a
    parameter; every mistake one :class:`ParameterError` naming the file and the key."""

    def __init__(self, scene: _Scene, data, where: str, keys: tuple[str, ...] | None, hint: str = ""):
        self.scene, self.where = scene, where
        if not isinstance(data, dict):
            scene.fail(where, f"{data!r} is not a table")
        unknown = [k for k in data if keys is not None and k not in keys]
        if unknown:
            self.fail(unknown[0], f"unknown key: allowed keys are {', '.join(keys)}{hint}")
        self.data = data

    def fail(self, key: str, message: str):
        self.scene.fail(self.scene.join(self.where, key), message)

    def has(self, key: str) -> bool:
        return key in self.data

    def _get(self, key: str, default):
        if key not in self.data and default is _MISSING:
            self.fail(key, "missing")
        return self.data.get(key, default)

    def string(self, key: str, default=_MISSING, choices: tuple[str, ...] | None = None) -> str:
        value = self._get(key, default)
        if key not in self.data:
            return value
        if not isinstance(value, str):
            self.fail(key, f"{value!r} is not a string")
        if choices is not None and value not in choices:
            self.fail(key, f"{value!r}: choose one of {', '.join(choices)}")
        return value

    def boolean(self, key: str, default=_MISSING) -> bool:
        value = self._get(key, default)
        if not isinstance(value, bool):
            self.fail(key, f"{value!r} is not true or false")
        return value

    def integer(self, key: str, lo: int, hi: int, default=_MISSING) -> int | None:
        value = self._get(key, default)
        if key in self.data:
            self.check_integer(key, value, lo, hi)
        return value

    def check_integer(self, key: str, value, lo: int, hi: int) -> None:
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            self.fail(key, f"{value!r}: must be an integer in [{lo}, {hi}]")

    def number(self, key: str, default=_MISSING, lo: float = -math.inf, hi: float = math.inf) -> float:
        value = self._get(key, default)
        return value if key not in self.data else self.to_number(key, value, lo, hi)

    def to_number(self, key: str, value, lo: float = -math.inf, hi: float = math.inf) -> float:
        """A number, or the value of the parameter a string names (``"q"``, ``"-v0"``)."""
        if isinstance(value, str):
            value = self.scene.parameter(self, key, value)
        elif isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail(key, f"{value!r} is not a number: write a finite number or a parameter's name in quotes")
        if not lo <= value <= hi:
            self.fail(key, f"{value!r} is out of range: must be in [{lo:g}, {hi:g}]")
        return float(value)

    def array(self, key: str, default=_MISSING) -> list:
        value = self._get(key, default)
        if not isinstance(value, list):
            self.fail(key, f"{value!r} is not an array")
        return value

    def numbers(self, key: str, size: int | None = None) -> tuple[float, ...]:
        values = self.array(key)
        if size is not None and len(values) != size:
            self.fail(key, f"{values!r}: give {size} numbers")
        return tuple(self.to_number(key, v) for v in values)

    def table(self, key: str, keys: tuple[str, ...] | None, hint: str = "", default=_MISSING) -> _Table:
        return _Table(self.scene, self._get(key, default), self.scene.join(self.where, key), keys, hint)

    def tables(self, key: str, keys: tuple[str, ...]) -> list[_Table]:
        """An array of tables ``[[key]]``; counted from 1 in messages (``load[1].q``)."""
        items = self._get(key, [])
        if not isinstance(items, list):
            self.fail(key, f"write [[{key}]] (an array of tables), not [{key}]")
        return [_Table(self.scene, item, f"{self.scene.join(self.where, key)}[{i}]", keys)
                for i, item in enumerate(items, 1)]


class _Scene:
    """Reads one file's document into a :class:`Case`, in order: params, section, the rest."""

    def __init__(self, file: str, doc: dict):
        self.file = file
        self.top = _Table(self, doc, "", TOP)
        self.params: dict = {}
        self.named: set[str] = set()  # the parameters some value names
        self.bodies: tuple[str, ...] = ()  # the names of [[bodies]], none with [section]
        self.body_regions: tuple[Region, ...] = ()  # the bodies that give their own material
        self.files_read: list[tuple[str, str]] = []  # (path, sha256) of the other files read

    def fail(self, where: str, message: str):
        raise ParameterError(_one_line(f"{self.file}: {where}: {message}"))

    @staticmethod
    def join(where: str, key: str) -> str:
        return f"{where}.{key}" if where else key

    def parameter(self, table: _Table, key: str, text: str) -> float:
        """The value of the parameter that ``text`` names, negated for a leading ``-``, in
        radians for a trailing `` deg`` (an angle given in degrees: ``"patch_deg deg"``)."""
        scale, text = (math.pi / 180, text[:-4].rstrip()) if text.endswith(" deg") else (1.0, text)
        sign, name = (-scale, text[1:]) if text.startswith("-") else (scale, text)
        value = self.params.get(name)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            numeric = ", ".join(k for k, v in self.params.items() if not isinstance(v, bool))
            table.fail(key, f"{text!r} names no parameter: write a number, or in quotes a key of [params] "
                            f"({numeric}), with a leading - for its negative")
        self.named.add(name)
        return sign * value

    def build(self, overrides: dict, source: Source) -> Case:
        top = self.top
        name = top.string("name")
        if not NAME.fullmatch(name):
            top.fail("name", f"{name!r}: letters, digits, '_', '-' and '.' only (it names the output directory)")
        if isinstance(top.data.get("body"), list):  # [[body]] for [[bodies]]
            top.fail("body", "write body = \"ring\" or \"prism\"; a scene's several bodies are [[bodies]] tables")
        self.body = body = top.string("body", choices=(RING, PRISM))
        features = {"cutout": bool(top.data.get("cutout")), "wall": top.has("wall"),
                    "contact": bool(top.data.get("contact"))}
        params = top.table("params", tuple(COMMON) + tuple(SCENE_KEYS))
        self.params = p = self.read_params(params, features, name, overrides)
        if body == PRISM:
            self.length = top.number("length", lo=0.0)
            if self.length <= 0:
                top.fail("length", f"{self.length!r} is out of range: the prism's length must be > 0")
        elif top.has("length"):
            top.fail("length", "a ring goes 2 pi round: length is for body = \"prism\" only")
        else:
            self.length = TWO_PI
        self.section = self.read_sections(top)
        material = top.table("material", ("E_T", "variation"), default={},
                             hint=" (E, nu, rho, tau_s and plastic are parameters: give them in [params])")
        E_T = material.number("E_T", 0.0, lo=0.0)
        if E_T >= p["E"]:
            material.fail("E_T", f"{E_T!r} is out of range: the tangent modulus must be below E={p['E']:g}")
        variation = self.read_variation(material)
        loads = tuple(self.read_load(t) for t in top.tables("load", ("q", "edge", "x3_intervals", "mode", "amplitude",
                                                                    "speed")))
        forces = tuple(self.read_force(t) for t in top.tables("body_force", ("pattern", "time", "amplitude"))) + \
            tuple(self.read_force(t, self.edge(t, "edge")) for t in top.tables("traction", ("edge", "pattern", "time",
                                                                                           "amplitude")))
        cutouts = tuple(self.read_cutout(t) for t in top.tables("cutout", ("s_range", "t_range", "x3_intervals")))
        regions = self.read_regions(top.tables("region", REGION_KEYS))
        wall = self.read_wall(top.table("wall", ("edge", "gap", "friction", "slope"))) if features["wall"] else None
        contacts = self.read_contacts(top.tables("contact", CONTACT_KEYS))
        probes = tuple(self.read_probe(t) for t in top.tables("probe", PROBE_KEYS))
        if not probes:
            top.fail("probe", "missing: a scene needs at least one [[probe]] (the columns of history.csv)")
        case = Case(
            name=name, title=top.string("title", name), body=body, section=self.section,
            material=Material(p["E"], p["nu"], p["rho"], p["tau_s"], E_T=E_T, plastic=p["plastic"]),
            loads=loads, supports=tuple(self.read_support(t) for t in top.tables("support", ("edge", "components"))),
            probes=probes, params=p, length=self.length, cutouts=tuple(c for c in cutouts if c is not None),
            contrast=p.get("contrast", 1.0),
            initial_velocity=tuple(self.read_velocity(t) for t in top.tables("initial_velocity", VELOCITY_KEYS)),
            wall=wall, forces=forces, variation=variation, regions=regions, contacts=contacts,
            units=top.string("units", Case.__dataclass_fields__["units"].default),
            references=self.read_references(top, probes), source=replace(source, files=tuple(self.files_read)),
            **self.read_symmetry(top, loads, cutouts, wall, forces, variation),
        )
        self.check_unused(params, features)
        return case

    def read_params(self, table: _Table, features: dict, name: str, overrides: dict) -> dict:
        """The file's parameters, each checked by its spec as ``--set`` checks it, then merged
        with ``overrides`` by :func:`validate`."""
        specs, defaults = dict(COMMON), dict(OPTIONAL)
        for key, value in table.data.items():
            specs[key] = COMMON.get(key) or SCENE_KEYS[key]
            try:
                defaults[key] = specs[key].check(key, value)
            except ParameterError as exc:
                table.fail(key, str(exc))
        for key in REQUIRED + tuple(k for k, needs in BOUND.items() if any(features[f] for f in needs)):
            if key not in table.data:
                why = f" (a scene with {_features(key, features, True)} needs it)" if key in BOUND else ""
                table.fail(key, f"missing{why}: {(COMMON.get(key) or SCENE_KEYS[key]).help}")
        try:
            validate(specs, defaults, {}, name)
        except ParameterError as exc:
            self.fail("params", str(exc))
        return validate(specs, defaults, overrides, name)

    def check_unused(self, table: _Table, features: dict) -> None:
        """Refuse a scene key that nothing reads: a --set of it would change nothing."""
        for key in table.data:
            if key in COMMON or key in self.named:
                continue
            if key not in BOUND:
                table.fail(key, f"no value of the scene names it (write e.g. q = \"{key}\" where it belongs)")
            if not any(features[f] for f in BOUND[key]):
                table.fail(key, f"the scene has no {_features(key, features, False)} to use it")

    def read_sections(self, top: _Table):
        """``[section]`` (one body), or ``[[bodies]]`` (several): one of them, not both."""
        if top.has("section") == top.has("bodies"):
            top.fail("bodies" if top.has("bodies") else "section",
                     "give either [section] (one body) or [[bodies]] (several), "
                     + ("not both" if top.has("section") else "missing both"))
        if top.has("section"):
            return self.read_section(top.table("section", ("kind", "s", "t", "edges", "file")))
        return self.read_bodies(top, top.tables("bodies", BODY_KEYS))

    def read_bodies(self, top: _Table, tables: list[_Table]):
        """``[[bodies]]``: at least two named mapped blocks, assembled into one mesh section
        (:func:`cases.bodies.assemble`: each body a region, its edge ``e`` the edge ``'body.e'``);
        a body that gives material constants is a region of its own material."""
        if len(tables) < 2:
            top.fail("bodies", f"{len(tables)} given: a scene of several bodies needs at least two (one body: "
                               "write [section])")
        bodies, regions = [], []
        for t in tables:
            name = t.string("name")
            if not WORD.fullmatch(name) or name in (b.name for b in bodies):
                t.fail("name", f"{name!r}: a word of letters, digits and '_' (no '.'), one per body")
            bodies.append(Body(name, self.read_block(t, t.string("kind", choices=("rect", "polar")))))
            if any(t.has(k) for k in MATERIAL_KEYS):
                regions.append(Region(name, self.read_material(t)))
        self.bodies, self.body_regions = tuple(b.name for b in bodies), tuple(regions)
        try:
            with _quiet():
                return assemble(bodies, path=self.file)
        except UnsupportedCase as exc:  # the names are checked above; anything else is still one line
            top.fail("bodies", str(exc))

    def read_section(self, t: _Table):
        kind = t.string("kind", choices=("rect", "polar", "mesh"))
        if kind == "mesh":
            return self.read_mesh_section(t)
        if t.has("file"):
            t.fail("file", f"for kind = \"mesh\" only (a {kind} block is given by s, t and edges)")
        return self.read_block(t, kind)

    def read_block(self, t: _Table, kind: str) -> Section:
        """A mapped block of ``kind`` (rect, polar): axes ``s`` and ``t``, named ``edges``."""
        s, tt = self.read_axis(t, "s"), self.read_axis(t, "t")
        if kind == "polar" and s.breaks[0] <= 0:
            t.fail("s.breaks", f"{s.breaks[0]!r}: a polar section's radius s must be > 0")
        if kind == "polar" and not 0 <= tt.breaks[0] <= tt.breaks[-1] <= math.pi:
            t.fail("t.breaks", "a polar section's angle t from the axis must lie in [0, pi]")
        if self.body == RING and kind == "rect" and s.breaks[0] < 0:
            t.fail("s.breaks", f"{s.breaks[0]!r}: the radius r = s of a ring's section must be >= 0")
        edges = t.table("edges", None, default={})
        for name in edges.data:
            edges.string(name, choices=EDGES)
            if name in EDGES or name == "all" or not WORD.fullmatch(name):
                edges.fail(name, "not a name for an edge: a word of letters, digits and '_', not all or "
                                 + ", ".join(EDGES))
        return Section(kind, s, tt, dict(edges.data))

    def read_mesh_section(self, t: _Table):
        """``kind = "mesh"``: a gmsh mesh ``file`` (relative to the scene file), read and checked
        by :func:`cases.msh_section.read_msh`; its physical curves name the edges."""
        from .msh_section import read_msh

        for key in ("s", "t", "edges"):
            if t.has(key):
                t.fail(key, "not for kind = \"mesh\": the mesh's physical curves name its edges")
        name = t.string("file")
        path = Path(name) if Path(name).is_absolute() else Path(self.file).parent / name
        if path.suffix.lower() != ".msh":
            t.fail("file", f"{name!r}: give a gmsh mesh file (.msh)")
        try:
            section = read_msh(path, self.body)
        except (ParameterError, UnsupportedCase) as exc:
            t.fail("file", str(exc))
        self.files_read.append((str(path), hashlib.sha256(path.read_bytes()).hexdigest()))
        return section

    def read_regions(self, tables: list[_Table]) -> tuple[Region, ...]:
        """``[[region]]``: a part of the section of its own material (the other constants as the
        body's, ``[params]``): a physical surface ``name`` of a mesh section, or on a block the
        box ``s_range`` x ``t_range``. A scene of several bodies gives a body's material in its
        ``[[bodies]]`` table instead (one place for it)."""
        if self.bodies:
            if tables:
                self.fail("region", "not with [[bodies]]: give a body's own material (E, nu, rho, tau_s, E_T) in "
                                    "its [[bodies]] table")
            return self.body_regions
        mesh = self.section.kind == "mesh"
        out = []
        for t in tables:
            name = t.string("name")
            if not WORD.fullmatch(name) or name in (r.name for r in out):
                t.fail("name", f"{name!r}: a word of letters, digits and '_', one per region")
            if mesh:
                for key in ("s_range", "t_range"):
                    if t.has(key):
                        t.fail(key, "not for a mesh section: its region is the physical surface name")
                if name not in self.section.regions:
                    t.fail("name", f"{name!r} is not a physical surface of the mesh (it has "
                                   f"{', '.join(self.section.regions)})")
                box = (None, None)
            else:
                box = self.read_box(t, empty=False)
            out.append(Region(name, self.read_material(t), *box))
        if not mesh:
            for i, a in enumerate(out):
                for b in out[:i]:
                    if all(max(x[0], y[0]) < min(x[1], y[1]) for x, y in ((a.s_range, b.s_range), (a.t_range, b.t_range))):
                        self.fail("region", f"regions {b.name!r} and {a.name!r} overlap")
        return tuple(out)

    def read_material(self, t: _Table) -> Material:
        """A region's or a body's own material: ``E``, ``nu``, ``rho``, ``tau_s``, ``E_T``, each
        as ``[params]`` (E_T: 0) where not given; the body's law (``plastic``)."""
        p = self.params
        E = t.number("E", p["E"], lo=0.0)
        E_T = t.number("E_T", 0.0, lo=0.0)
        if E <= 0 or E_T >= E:
            t.fail("E" if E <= 0 else "E_T", "need E > 0 and 0 <= E_T < E")
        nu = t.number("nu", p["nu"], lo=-0.9999, hi=0.49999)
        return Material(E, nu, t.number("rho", p["rho"], lo=1e-12), t.number("tau_s", p["tau_s"], lo=0.0),
                        E_T=E_T, plastic=p["plastic"])

    def read_axis(self, section: _Table, key: str) -> Axis:
        t = section.table(key, ("breaks", "counts", "refinable"))
        breaks = t.numbers("breaks")
        if len(breaks) < 2 or any(b <= a for a, b in zip(breaks, breaks[1:])):
            t.fail("breaks", f"{list(breaks)!r}: give at least two numbers, strictly increasing")
        counts = t.array("counts")
        if len(counts) != len(breaks) - 1:
            t.fail("counts", f"{counts!r}: give one count per segment between breaks ({len(breaks) - 1})")
        for n in counts:
            t.check_integer("counts", n, 1, MAX_COUNT)
        return Axis(breaks, tuple(counts), t.boolean("refinable", True))

    def edge(self, t: _Table, key: str, allow_all: bool = False) -> str:
        parametric = () if self.section.kind == "mesh" else EDGES  # a mesh's edges are its physical curves
        names = tuple(self.section.edges) + parametric + (("all",) if allow_all else ())
        return t.string(key, choices=names)

    def intervals(self, t: _Table, key: str, moving: bool = False) -> tuple[tuple[float, float], ...]:
        """Intervals along x3 inside the body (prism: [0, length]; ring: [-2 pi, 2 pi], at most
        once round), none overlapping; a moving load's prism intervals may start outside the
        body (a patch that enters it)."""
        pairs = t.array(key)
        lo, hi, text = (0.0, self.length, f"[0, length = {self.length:g}]") if self.body == PRISM else \
            (-TWO_PI, TWO_PI, "[-2 pi, 2 pi] (radians)")
        if moving and self.body == PRISM:
            lo, hi, text = -math.inf, math.inf, "(-inf, inf) (a moving load's)"
        out = []
        for pair in pairs:
            if not isinstance(pair, list) or len(pair) != 2:
                t.fail(key, f"{pair!r}: each interval is a pair [a, b]")
            a, b = (t.to_number(key, v) for v in pair)
            if not lo <= a < b <= hi:
                t.fail(key, f"[{a:g}, {b:g}] is outside the body or empty: need a < b within {text}")
            out.append((a, b))
        if not out:
            t.fail(key, "empty: give at least one interval [a, b]")
        total = sum(b - a for a, b in out)
        covered = _measure(_on_circle(out) if self.body == RING else _merged(out))
        if covered < total - 1e-12 * (hi - lo):
            t.fail(key, f"{[list(p) for p in out]!r}: the intervals overlap (a ring's angles count modulo 2 pi)")
        return tuple(out)

    def read_load(self, t: _Table) -> Pressure:
        q = t.number("q", lo=-MAX_STRESS, hi=MAX_STRESS)
        edge = self.edge(t, "edge")
        if t.has("mode") == t.has("x3_intervals"):
            t.fail("x3_intervals", "give either x3_intervals (where along x3 the pressure acts) or mode (one "
                                   "Fourier term), " + ("not both" if t.has("mode") else "missing both"))
        mode = t.integer("mode", 0 if self.body == RING else 1, 2000, None)
        speed = t.number("speed", 0.0, lo=-MAX_SPEED, hi=MAX_SPEED)
        if speed and mode is not None:
            t.fail("speed", "a single Fourier term (mode) cannot move: give x3_intervals for a moving patch")
        intervals = () if mode is not None else self.intervals(t, "x3_intervals", moving=bool(speed))
        return Pressure(q, edge, intervals, mode, self.amplitude(t), speed)

    def amplitude(self, t: _Table) -> Amplitude | None:
        """``amplitude = [[t, factor], ...]``: the load's factor in time, linear between the points
        and constant after the last (none: a step held from t = 0)."""
        if not t.has("amplitude"):
            return None
        points = t.array("amplitude")
        if not all(isinstance(p, list) and len(p) == 2 for p in points):
            t.fail("amplitude", "give [t, factor] pairs, e.g. [[0, 0], [2e-4, 1], [6e-4, 0]]")
        pairs = tuple((t.to_number("amplitude", a), t.to_number("amplitude", b)) for a, b in points)
        try:
            return Amplitude(pairs)
        except ValueError as exc:
            t.fail("amplitude", f"{[list(p) for p in pairs]!r}: {exc}")

    def read_force(self, t: _Table, edge: str | None = None) -> Force:
        """``pattern``: three expressions of x1, x2, x3 (the force per unit volume, or with
        ``edge`` per unit area of that edge's surface, in the body's components); ``time``: an
        expression of t that scales it (default 1)."""
        pattern = t.array("pattern")
        if len(pattern) != 3 or not all(isinstance(c, str) for c in pattern):
            t.fail("pattern", "give three expressions of x1, x2, x3 as strings, e.g. [\"0\", \"-9.81 * 7800\", \"0\"]")
        from . import expressions, manufactured  # sympy: only for a scene that has a body force

        time = t.string("time", "1")
        for key, texts, allowed in (("pattern", pattern, ("x1", "x2", "x3")), ("time", [time], ("t",))):
            for text in texts:
                # read from a whitelist, never run (cases/expressions.py); then once by numpy,
                # as every solver will
                try:
                    expressions.parse(text, allowed)
                    manufactured.numeric(text)
                except expressions.VariableError as exc:
                    t.fail(key, f"{excerpt(text)} uses {exc.name}: {key} may use {', '.join(allowed)} only")
                except expressions.ExpressionError as exc:
                    t.fail(key, f"{excerpt(text)} is not an expression: {exc}")
        self.check_finite(t, pattern, time)
        return Force(tuple(pattern), time, edge, self.amplitude(t))

    def check_finite(self, t: _Table, pattern, time: str) -> None:
        """Refuse a force no solver could apply, before any run: a pattern that is not finite
        at sample points inside the body (``exp(1000*x1)``), a time factor that cannot be
        evaluated or is not finite over [0, t_end] (``1/t``), evaluated as the solvers do."""
        import numpy as np

        from .manufactured import numeric, time_function

        x1, x2 = (np.reshape(v, (-1, 1)) for v in self.section.inside(7))
        x3 = self.length * (np.arange(16) + 0.5) / 16
        for text in pattern:
            try:
                with np.errstate(all="ignore"):  # an overflow is refused below, not warned of
                    values = np.asarray(numeric(text)(x1, x2, x3, 0.0), float)
            except (ArithmeticError, TypeError, ValueError) as exc:
                t.fail("pattern", f"{excerpt(text)} cannot be evaluated inside the body ({failure(exc)})")
            bad = ~np.isfinite(values)
            if bad.any():
                i, k = np.argwhere(np.broadcast_to(bad, np.broadcast_shapes(x1.shape, x3.shape)))[0]
                t.fail("pattern", f"{excerpt(text)} is not finite inside the body (at x1 = {x1[i, 0]:g}, "
                                  f"x2 = {x2[i, 0]:g}, x3 = {x3[k]:g})")
        factor = time_function(time)
        for when in np.linspace(0.0, self.params["t_end"], 201):
            try:
                with np.errstate(all="ignore"):  # an overflow is refused below, not warned of
                    value = factor(float(when))
            except (ArithmeticError, TypeError, ValueError) as exc:
                t.fail("time", f"{excerpt(time)} cannot be evaluated at t = {when:g} ({failure(exc)})")
            if not math.isfinite(value):
                t.fail("time", f"{excerpt(time)} is not finite at t = {when:g}")

    def read_variation(self, material: _Table) -> tuple[tuple[float, int], ...]:
        """``variation = [[a, m], ...]``: E and rho times ``1 + sum a cos(m k x3)``."""
        terms = []
        for term in material.array("variation", []):
            if not (isinstance(term, list) and len(term) == 2):
                material.fail("variation", f"{term!r}: give [amplitude, mode] pairs, e.g. [[0.3, 2]]")
            a = material.to_number("variation", term[0], lo=-1.0, hi=1.0)
            material.check_integer("variation", term[1], 1, 2000)
            terms.append((a, int(term[1])))
        if sum(abs(a) for a, _ in terms) >= 1.0:
            material.fail("variation", "the amplitudes' sum of magnitudes must be below 1 (E and rho stay positive)")
        return tuple(terms)

    def read_support(self, t: _Table) -> Support:
        edge = self.edge(t, "edge", allow_all=True)
        components = t.array("components")
        for c in components:
            t.check_integer("components", c, 1, 3)
        if not components or len(set(components)) != len(components):
            t.fail("components", f"{components!r}: give distinct components among 1, 2, 3")
        return Support(edge, tuple(components))

    def read_cutout(self, t: _Table) -> Cutout | None:
        """A cut-out, or None where its section box is empty (so ``notch_depth = 0`` is no notch)."""
        box = self.read_box(t, empty=True)
        intervals = self.intervals(t, "x3_intervals")
        return None if any(a == b for a, b in box) else Cutout(box[0], box[1], intervals)

    def read_box(self, t: _Table, empty: bool) -> list[tuple[float, float]]:
        """``s_range`` and ``t_range``, a box inside the section (a mesh section's: its bounding
        box); ``empty``: a range may be a point (a cut-out of zero extent is none)."""
        box = []
        spans = self.section.bounds if self.section.kind == "mesh" else (self.section.s.span, self.section.t.span)
        for key, (lo, hi) in zip(("s_range", "t_range"), spans):
            a, b = t.numbers(key, 2)
            if not (lo <= a <= b <= hi if empty else lo <= a < b <= hi):
                rule = f"{lo:g} <= a <= b <= {hi:g}" if empty else f"{lo:g} <= a < b <= {hi:g}"
                t.fail(key, f"[{a:g}, {b:g}] is outside the section{'' if empty else ' or empty'}: need {rule}")
            box.append((a, b))
        return box

    def read_velocity(self, t: _Table) -> InitialVelocity:
        """A uniform initial velocity of the whole section, or of one body (``region``)."""
        return InitialVelocity(t.integer("component", 1, 3), t.number("value"), self.region(t))

    def region(self, t: _Table) -> str | None:
        """The body (a mesh section's physical surface) that ``region`` names; None without it."""
        if not t.has("region"):
            return None
        if self.section.kind != "mesh":
            t.fail("region", "one mapped block has no regions: region names a body of [[bodies]] or a physical "
                             "surface of a mesh section")
        name, names = t.string("region"), tuple(self.section.regions)
        if name not in names:
            what = ("a body of the scene", "bodies") if self.bodies else ("a physical surface of the mesh", "surfaces")
            t.fail("region", f"{name!r} is not {what[0]} (its {what[1]}: {', '.join(names)})")
        return name

    def read_contacts(self, tables: list[_Table]) -> tuple[ContactPair, ...]:
        """``[[contact]]``: a face of one body against a face of another (``'body.edge'``), each
        face in one pair at most, their geometry checked as :func:`cases.bodies.check_pairs`
        checks it (faces of separate bodies that face each other node for node, overlapping by
        no more than the stated ``interference``). The bodies of a gmsh section touch nowhere
        else (:func:`cases.bodies.check_touching`)."""
        if tables and self.section.kind != "mesh":
            self.fail("contact", "a contact pair joins two bodies: give them as [[bodies]] tables, or as physical "
                                 "surfaces of a mesh section (a rigid wall is [wall])")
        pairs: list[ContactPair] = []
        for t in tables:
            face, other = self.edge(t, "face"), self.edge(t, "other")
            for key, edge in (("face", face), ("other", other)):
                taken = next((i for i, p in enumerate(pairs, 1) if edge in (p.face, p.other)), None)
                if taken is not None:
                    t.fail(key, f"{edge!r} is in contact[{taken}] already: a face is in one pair at most")
            if body_of(face) == body_of(other):
                t.fail("other", f"{other!r} is of the body {body_of(face)!r} as the face is: a pair joins two bodies")
            pairs.append(ContactPair(face, other, t.number("friction", 0.0, lo=0.0),
                                     t.number("interference", 0.0, lo=0.0)))
            self.check_pair(t, pairs[-1])
        if not self.bodies and self.section.kind == "mesh":
            try:
                check_touching(self.file, self.section, pairs)
            except UnsupportedCase as exc:
                self.fail("section.file", str(exc).removeprefix(f"{self.file}: "))
        return tuple(pairs)

    def check_pair(self, t: _Table, pair: ContactPair) -> None:
        """The pair's geometry by :func:`cases.bodies.check_pairs`, its refusal the file's line."""
        try:
            with _quiet():  # a case's name, section and pairs: what check_pairs reads of it
                check_pairs(SimpleNamespace(name=self.file, section=self.section, contacts=(pair,)))
        except UnsupportedCase as exc:
            self.fail(t.where, str(exc).removeprefix(f"{self.file}: "))

    def read_wall(self, t: _Table) -> Wall:
        return Wall(self.edge(t, "edge"), t.number("gap", lo=0.0), t.number("friction", lo=0.0),
                    t.number("slope", 0.0, lo=0.0))

    def read_probe(self, t: _Table) -> Probe:
        name = t.string("name")
        if not WORD.fullmatch(name) or name == "t":
            t.fail("name", f"{name!r}: a word of letters, digits and '_' (a column of history.csv), not t")
        kind = t.string("kind", choices=tuple(PROBE_FIELDS))
        field = t.string("field", choices=PROBE_FIELDS[kind])
        needs = {"point": ("point",), "edge_mean": ("edge",)}.get(kind, ())
        for key in ("point", "edge"):
            if t.has(key) != (key in needs):
                t.fail(key, f"a {kind} probe needs a {key}" if key in needs else f"not for a {kind} probe")
        component = tuple(t.array("component", []))
        if field in ("u", "v"):
            if len(component) != 1:
                t.fail("component", f"{list(component)!r}: a vector field needs one component, e.g. [2]")
            t.check_integer("component", component[0], 1, 3)
        elif field == "sigma" and kind == "edge_mean":
            if component != ("n", "n"):
                t.fail("component", f"{list(component)!r}: the mean stress on an edge is [\"n\", \"n\"] (normal)")
        elif field == "sigma":
            if len(component) != 2:
                t.fail("component", f"{list(component)!r}: a stress needs two components, e.g. [2, 2]")
            for c in component:
                t.check_integer("component", c, 1, 3)
        elif component:
            t.fail("component", "the plastic strain intensity has no component")
        point = t.numbers("point", 3) if kind == "point" else None
        if point is not None:
            self.check_point(t, point)
        if t.has("region") and kind != "body_mean":
            t.fail("region", f"not for a {kind} probe (a body_mean probe's body)")
        return Probe(name, kind, field, component, point, self.edge(t, "edge") if kind == "edge_mean" else None,
                     self.region(t))

    def check_point(self, t: _Table, point: tuple[float, float, float]) -> None:
        """The point lies in the section (to round-off) and along x3 in the body."""
        with _quiet():
            inside = self.section.contains(point[0], point[1])
        if not inside:
            t.fail("point", f"{list(point)!r} is outside the section")
        lo, hi = (0.0, self.length) if self.body == PRISM else (-TWO_PI, TWO_PI)
        if not lo <= point[2] <= hi:
            t.fail("point", f"x3 = {point[2]:g} is outside the body: need {lo:g} <= x3 <= {hi:g}")

    def read_symmetry(self, top: _Table, loads, cutouts, wall: Wall | None, forces=(), variation=()) -> dict:
        """``symmetric`` and ``axisymmetric`` (ring only), each checked against the loads and
        cut-outs: a wrong claim would make a solver leave out harmonics that carry the answer."""
        if self.body == PRISM:
            for key in ("symmetric", "axisymmetric"):
                if top.has(key):
                    top.fail(key, "for body = \"ring\" only (a prism's series is symmetric about mid-span)")
            return {}
        symmetric, axisymmetric = top.boolean("symmetric", False), top.boolean("axisymmetric", False)
        pieces = [(f"load[{i}]", x.mode, x.x3_intervals) for i, x in enumerate(loads, 1)] + \
                 [(f"cutout[{i}]", None, x.x3_intervals) for i, x in enumerate(cutouts, 1) if x is not None]
        for i, load in enumerate(loads, 1):
            if symmetric and load.moving:
                top.fail("symmetric", f"true, but load[{i}] moves along x3 (set symmetric = false)")
        for where, mode, intervals in pieces:
            circle = _on_circle(intervals)
            if axisymmetric and not (mode == 0 or _same(circle, [(0.0, TWO_PI)])):
                top.fail("axisymmetric", f"true, but {where} varies along x3 (give it mode = 0 or x3_intervals = "
                                         "[[0, 2 pi]], or set axisymmetric = false)")
            if symmetric and mode is None and not _same(circle, _on_circle([(-b, -a) for a, b in intervals])):
                top.fail("symmetric", f"true, but {where} is not symmetric about x3 = 0 (set symmetric = false)")
        if forces:
            from .manufactured import forces_invariant  # sympy: only for a scene that has forces
        for i, force in enumerate(forces, 1):
            even = forces_invariant((force,), self.section, TWO_PI, lambda z: -z, (1, 1, -1))
            # the same all round: unchanged by any turn, and no hoop component
            uniform = all(forces_invariant((force,), self.section, TWO_PI, lambda z, a=a: z + a * TWO_PI)
                          for a in UNIFORM_SHIFTS) and forces_invariant((force,), self.section, TWO_PI,
                                                                        lambda z: z, (1, 1, -1))
            if symmetric and not even:
                top.fail("symmetric", f"true, but force {i} (body_force, then traction) is not symmetric about "
                                      "x3 = 0 (u_r, u_z even, "
                                      "u_theta odd; set symmetric = false)")
            if axisymmetric and not uniform:
                top.fail("axisymmetric", f"true, but force {i} (body_force, then traction) varies along x3 "
                                         "or turns about the axis")
        if axisymmetric and variation:
            top.fail("axisymmetric", "true, but the material varies along x3 (variation)")
        if axisymmetric and wall is not None and wall.slope > 0:
            top.fail("axisymmetric", f"true, but the wall's slope is {wall.slope:g} > 0 (set axisymmetric = false)")
        return {"symmetric": symmetric, "axisymmetric": axisymmetric}

    def read_references(self, top: _Table, probes: tuple[Probe, ...]) -> dict:
        """What the runs and reports read besides the scene: ``plastic_zone_times`` (s),
        ``comparison_window_s`` and ``singular_probes`` (probe -> why it has no converged truth)."""
        t = top.table("references", ("plastic_zone_times", "comparison_window_s", "singular_probes"), default={})
        out = {}
        if t.has("plastic_zone_times"):
            out["plastic_zone_times"] = tuple(t.to_number("plastic_zone_times", v, lo=0.0)
                                              for v in t.array("plastic_zone_times"))
        if t.has("comparison_window_s"):
            out["comparison_window_s"] = t.number("comparison_window_s", lo=0.0)
        if t.has("singular_probes"):
            singular = t.table("singular_probes", tuple(p.name for p in probes))
            out["singular_probes"] = {k: singular.string(k) for k in singular.data}
        return out


def _quiet():
    """Numpy's floating-point warnings off while a mesh section is built or searched: an absurd
    geometry (breaks of 1e300) is refused, or taken as the block sections take it, in one line."""
    import numpy as np

    return np.errstate(all="ignore")


def _features(key: str, features: dict, present: bool) -> str:
    """The features that read parameter ``key``, those the scene has (``present``) or all."""
    return " or ".join(FEATURES[f] for f in BOUND[key] if features[f] or not present)


def _merged(pieces) -> list[tuple[float, float]]:
    """Sorted intervals with the overlapping or touching ones joined."""
    out: list[tuple[float, float]] = []
    for a, b in sorted(pieces):
        if out and a <= out[-1][1]:
            out[-1] = (out[-1][0], max(b, out[-1][1]))
        else:
            out.append((a, b))
    return out


def _on_circle(intervals) -> list[tuple[float, float]]:
    """Angular intervals as merged pieces of [0, 2 pi)."""
    pieces = []
    for a, b in intervals:
        if b - a >= TWO_PI:
            return [(0.0, TWO_PI)]
        a0 = a % TWO_PI
        b0 = a0 + (b - a)
        pieces += [(a0, b0)] if b0 <= TWO_PI else [(a0, TWO_PI), (0.0, b0 - TWO_PI)]
    return _merged(pieces)


def _measure(pieces) -> float:
    return sum(b - a for a, b in pieces)


def _same(x, y, tol: float = 1e-9) -> bool:
    return len(x) == len(y) and all(abs(a - c) <= tol and abs(b - d) <= tol for (a, b), (c, d) in zip(x, y))
