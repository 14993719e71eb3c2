"""Read a scene from a TOML file (the format is described in ``docs/scene-format.md``).

Every problem, from a misspelt key to a non-positive mass, is collected with the file and the key
it was found at, and reported in one :class:`~hexapod.errors.ModelError` (a file that cannot be
read or parsed: an :class:`~hexapod.errors.InputFileError`).

Each element is converted key by key. A key that cannot be converted is reported; an optional
one is left out so the element's other problems are reported in the same run, a required one
drops the element (and references to it are not reported again).
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np

from hexapod._support.files import read_toml
from hexapod.errors import ModelError, Problem
from hexapod.scene.bodies import Particle, PlanarBody, SpatialBody
from hexapod.scene.contacts import GroundForces
from hexapod.scene.drivers import DRIVER_TYPES
from hexapod.scene.element import Element, quoted
from hexapod.scene.forces import FORCE_TYPES
from hexapod.scene.joints import JOINT_TYPES
from hexapod.scene.joints.base import NUMBER, PAIR, VECTOR, VECTOR3
from hexapod.scene.laws import Constant, Law, law_types
from hexapod.scene.robots import robot_scene
from hexapod.scene.scene import Scene
from hexapod.spatial import (
    Placement,
    rotation_2d,
    rotation_about_axis,
    rotation_from_euler_parameters,
    rotation_from_rpy,
)


class _Invalid(ValueError):
    """A value that cannot be converted. ``key`` locates it inside the value (a sub-key)."""

    def __init__(self, message: str, key: str = ""):
        super().__init__(message)
        self.key = key


def _shown(value, limit: int = 60) -> str:
    """A value as a message shows it, its repr cut short: each problem stays on one line."""
    text = repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _key(name: str) -> str:
    """A TOML key as a location shows it: as written when it is a bare key, else quoted."""
    return name if re.fullmatch(r"[A-Za-z0-9_-]+", name) else _shown(name)


def _items(count: int, what: str) -> str:
    return f"{count} {what}" if count == 1 else f"{count} {what}s"


def _choices(sizes: tuple[int, ...], what: str) -> str:
    if len(sizes) == 1:
        return _items(sizes[0], what)
    return " or ".join(map(str, sizes[:-1])) + f" or {_items(sizes[-1], what)}"


# ------------------------------------------------------------------ value converters

def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _number(value) -> float:
    if not _is_number(value):
        raise _Invalid(f"must be a number, got {_shown(value)}")
    try:
        return float(value)
    except OverflowError:
        raise _Invalid(f"is too large for a floating-point number ({_shown(value, 20)})")\
            from None


def _vector(size: int | tuple[int, ...]):
    sizes = (size,) if isinstance(size, int) else size

    def convert(value) -> np.ndarray:
        if not (isinstance(value, list) and len(value) in sizes
                and all(_is_number(x) for x in value)):
            raise _Invalid(f"must be a list of {_choices(sizes, 'number')}, got {_shown(value)}")
        return np.array([_number(x) for x in value])

    return convert


def _numbers(value) -> tuple[float, ...]:
    if not (isinstance(value, list) and value and all(_is_number(x) for x in value)):
        raise _Invalid(f"must be a non-empty list of numbers, got {_shown(value)}")
    return tuple(_number(x) for x in value)


def _amplitudes(value) -> tuple[float, ...]:
    """A list of numbers that may be empty (harmonic amplitudes)."""
    return _numbers(value) if value != [] else ()


def _string(value) -> str:
    if not isinstance(value, str):
        raise _Invalid(f"must be a string, got {_shown(value)}")
    return value


def _strings(value) -> tuple[str, ...]:
    if isinstance(value, list) and value and all(isinstance(x, str) for x in value):
        return tuple(value)
    raise _Invalid(f"must be a non-empty list of names, got {_shown(value)}")


def _boolean(value) -> bool:
    if not isinstance(value, bool):
        raise _Invalid(f"must be true or false, got {_shown(value)}")
    return value


def _integer(value) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise _Invalid(f"must be an integer, got {_shown(value)}")
    return value


def _matrix3(value) -> np.ndarray:
    if not (isinstance(value, list) and len(value) == 3
            and all(isinstance(r, list) and len(r) == 3 and all(map(_is_number, r))
                    for r in value)):
        raise _Invalid("must be a 3 x 3 matrix (a list of 3 lists of 3 numbers), got "
                       f"{_shown(value)}")
    return np.array([[_number(x) for x in row] for row in value])


def _inertia(value):
    if isinstance(value, list) and value and isinstance(value[0], list):
        return _matrix3(value)
    return _vector((3, 6))(value)


def _nearest_rotation(R: np.ndarray) -> np.ndarray:
    """A matrix written with rounded digits, made exactly orthonormal (left as is when it is
    far from a rotation, so that validation reports it)."""
    if not np.all(np.isfinite(R)):
        return R
    U, _, Vt = np.linalg.svd(R)
    nearest = U @ Vt
    if np.linalg.det(nearest) > 0 and np.max(np.abs(nearest - R)) < 1e-6:
        return nearest
    return R


def _table_rotation(value: dict, keys: set) -> np.ndarray:
    """A spatial rotation from a table with exactly one way of giving it."""
    if keys == {"rpy"}:
        roll, pitch, yaw = _vector(3)(value["rpy"])
        return rotation_from_rpy(roll, pitch, yaw)
    if keys == {"quaternion"}:
        p = _vector(4)(value["quaternion"])
        if not np.all(np.isfinite(p)) or np.linalg.norm(p) < 1e-12:
            raise _Invalid("quaternion must be finite and non-zero")
        return rotation_from_euler_parameters(p / np.linalg.norm(p))
    if keys == {"matrix"}:
        return _nearest_rotation(_matrix3(value["matrix"]))
    if keys == {"axis", "angle"}:
        axis = _vector(3)(value["axis"])
        if not np.all(np.isfinite(axis)) or np.linalg.norm(axis) < 1e-12:
            raise _Invalid("axis must be finite and non-zero")
        return rotation_about_axis(axis, _number(value["angle"]))
    raise _Invalid("give exactly one of rpy, quaternion, matrix, or axis and angle")


def _rotation(dimension: int) -> Callable:
    """A rotation: in space ``{rpy = [...]}``, ``{quaternion = [e0, e1, e2, e3]}``,
    ``{matrix = [[...]]}`` or ``{axis = [...], angle = ...}``; in the plane an angle (rad)."""

    def convert(value):
        if dimension == 2:
            return rotation_2d(_number(value))
        if not isinstance(value, dict) or not value:
            raise _Invalid("must be a table with rpy, quaternion, matrix or axis and angle, "
                           f"got {_shown(value)}")
        keys = set(value)
        try:
            return _table_rotation(value, keys)
        except _Invalid as error:
            raise _Invalid(f"{'/'.join(sorted(keys))}: {error}") from None

    return convert


def _frame(dimension: int) -> Callable:
    """A frame reference: a marker name, a point ``[x, y(, z)]``, or a table
    ``{position = [...], rotation = ...}``."""

    def convert(value):
        if isinstance(value, str):
            return value
        if isinstance(value, list):
            return Placement(_vector(dimension)(value))
        if isinstance(value, dict):
            unknown = set(value) - {"position", "rotation"}
            if unknown:
                raise _Invalid(f"unknown key(s) {', '.join(map(_key, sorted(unknown)))}; a "
                               "frame has position and rotation")
            position = _vector(dimension)(value.get("position", [0.0] * dimension))
            rotation = _rotation(dimension)(value["rotation"]) if "rotation" in value else None
            return Placement(position, rotation)
        raise _Invalid(f"must be a marker name, a point or a table, got {_shown(value)}")

    return convert


def _point(dimension: int) -> Callable:
    def convert(value):
        if isinstance(value, str):
            return value
        return _vector(dimension)(value)

    return convert


def _constants(value) -> dict[str, float]:
    """A table of names and numbers (an expression law's constants, reference efforts)."""
    if not isinstance(value, dict):
        raise _Invalid(f"must be a table of names and numbers, got {_shown(value)}")
    out = {}
    for name, number in value.items():
        try:
            out[name] = _number(number)
        except _Invalid as error:
            raise _Invalid(str(error), key=name) from None
    return out


#: keys of each law table: converter and whether it is required
_LAW_KEYS = {
    "constant": {"value": (_number, True)},
    "guided": {},
    "polynomial": {"coefficients": (_numbers, True), "t0": (_number, False)},
    "harmonic": {"offset": (_number, False), "cos": (_amplitudes, False),
                 "sin": (_amplitudes, False), "frequency": (_number, True), "t0": (_number, False)},
    "spline": {"times": (_numbers, True), "values": (_numbers, True),
               "degree": (_integer, False), "boundary": (_string, False)},
    "hermite": {"times": (_numbers, True), "values": (_numbers, True), "rates": (_numbers, True),
                "accelerations": (_numbers, True), "periodic": (_boolean, False)},
    "gait": {"offset": (_number, False), "cos": (_amplitudes, False),
             "sin": (_amplitudes, False), "period": (_number, True), "duty": (_number, False),
             "shift": (_number, False), "blend": (_number, False)},
    "expression": {"expression": (_string, True), "constants": (_constants, False),
                   "period": (_number, False)},
}


def _plugin_keys(cls) -> dict:
    """The keys of a law class registered by a package: its dataclass fields, read by their
    annotated type (``str``, ``int`` or ``float``), required when they have no default."""
    readers = {"str": _string, "int": _integer, "float": _number, "tuple": _amplitudes}
    return {f.name: (readers.get(str(f.type), _number),
                     f.default is dataclasses.MISSING
                     and f.default_factory is dataclasses.MISSING)
            for f in dataclasses.fields(cls) if f.init}


def _law(value) -> Law:
    """A number (constant) or a table ``{type = "...", ...}``."""
    if not isinstance(value, dict):
        return Constant(_number(value))
    kind = value.get("type")
    types = law_types()
    if not isinstance(kind, str) or kind not in types:
        raise _Invalid(f"law type must be one of {', '.join(types)}, got {_shown(kind)}")
    spec = _LAW_KEYS[kind] if kind in _LAW_KEYS else _plugin_keys(types[kind])
    fields = {k: v for k, v in value.items() if k != "type"}
    article = "an" if kind[:1] in tuple("aeiou") else "a"
    unknown = set(fields) - set(spec)
    if unknown:
        raise _Invalid(f"unknown key(s) {', '.join(map(_key, sorted(unknown)))} for {article} "
                       f"{kind} law (expected {', '.join(spec)})")
    missing = [k for k, (_, required) in spec.items() if required and k not in fields]
    if missing:
        raise _Invalid(f"{article} {kind} law needs {', '.join(missing)}")
    args = {}
    for key, raw in fields.items():
        try:
            args[key] = spec[key][0](raw)
        except _Invalid as error:
            raise _Invalid(f"{key}{('.' + _key(error.key)) if error.key else ''} {error}") from None
    law = types[kind](**args)
    problems = law.problems()
    if problems:
        raise _Invalid("; ".join(problems))
    return law


def _laws(count: int) -> Callable:
    """``count`` components, each a number or a law; one component may be given bare."""

    def convert(value):
        if count == 1 and not isinstance(value, list):
            value = [value]
        if not isinstance(value, list) or len(value) != count:
            raise _Invalid(f"must be a list of {_items(count, 'number')} or laws, got "
                           f"{_shown(value)}")
        return tuple(_law(x) for x in value)

    return convert


def _markers(dimension: int) -> Callable:
    def convert(value):
        if not isinstance(value, dict):
            raise _Invalid(f"must be a table of named frames, got {_shown(value)}")
        frames = {}
        for name, frame in value.items():
            try:
                ref = _frame(dimension)(frame)
            except _Invalid as error:
                raise _Invalid(str(error), key=name) from None
            if isinstance(ref, str):
                raise _Invalid("must be a point or a frame, not a name", key=name)
            frames[name] = ref
        return frames

    return convert


# ------------------------------------------------------------------ element schemas

#: a schema: the element class, and per key its converter and whether it is required
Schema = tuple[type[Element], dict[str, tuple[Callable, bool]]]


def _body_schema(kind: str, scene_dimension: int) -> Schema:
    # a body's own dimension, so a planar body in a spatial scene reads and is then reported as
    # misplaced rather than as badly written
    dim = {"spatial": 3, "planar": 2}.get(kind, scene_dimension)
    common = {"name": (_string, True), "type": (_string, False), "mass": (_number, True),
              "position": (_vector(dim), False), "velocity": (_vector(dim), False),
              "markers": (_markers(dim), False), "mesh": (_string, False),
              "payload": (_number, False)}
    if kind == "particle":
        return Particle, common
    if kind == "planar":
        return PlanarBody, {**common, "inertia": (_number, True), "com": (_vector(2), False),
                            "angle": (_number, False), "angular_velocity": (_number, False)}
    return SpatialBody, {**common, "inertia": (_inertia, True), "com": (_vector(3), False),
                         "rotation": (_rotation(3), False),
                         "inertia_rotation": (_rotation(3), False),
                         "angular_velocity": (_vector(3), False)}


def _joint_schema(kind: str, dimension: int) -> Schema:
    schema = {"name": (_string, True), "type": (_string, True), "parent": (_string, True),
              "child": (_string, True), "parent_frame": (_frame(dimension), False),
              "child_frame": (_frame(dimension), False), "origin": (_vector(dimension), False),
              "rotation": (_rotation(dimension), False)}
    cls = JOINT_TYPES[kind]
    readers = {NUMBER: _number, VECTOR: _vector(dimension), VECTOR3: _vector(3), PAIR: _vector(2)}
    schema.update({key: (readers[value], required)
                   for key, (value, required) in cls.file_keys(dimension).items()})
    return cls, schema


def _driver_schema(kind: str, dimension: int) -> Schema:
    common = {"name": (_string, True), "type": (_string, False), "law": (_law, True)}
    if kind == "joint":
        return DRIVER_TYPES[kind], {**common, "joint": (_string, True)}
    if kind == "posture":  # a rule: no law
        return DRIVER_TYPES[kind], {"name": (_string, True), "type": (_string, True),
                                    "body": (_string, True), "joints": (_strings, True),
                                    "rest": (_numbers, True), "weights": (_numbers, False),
                                    "point": (_point(dimension), False)}
    return DRIVER_TYPES[kind], {**common, "body": (_string, True),
                                "coordinate": (_string, True),
                                "point": (_point(dimension), False),
                                "frame": (_string, False), "guide": (_boolean, False)}


def _force_schema(kind: str, dimension: int) -> Schema:
    torque_count = 3 if dimension == 3 else 1
    schemas = {
        "spring": {"body_a": (_string, True), "body_b": (_string, True),
                   "point_a": (_point(dimension), False), "point_b": (_point(dimension), False),
                   "stiffness": (_number, False), "damping": (_number, False),
                   "free_length": (_number, False), "force": (_law, False)},
        "applied-force": {"body": (_string, True), "force": (_laws(dimension), True),
                          "point": (_point(dimension), False), "frame": (_string, False)},
        "applied-torque": {"body": (_string, True), "torque": (_laws(torque_count), True),
                           "frame": (_string, False)},
        "effort": {"joint": (_string, True), "law": (_law, True)},
        "rotational-spring": {"joint": (_string, True), "stiffness": (_number, False),
                              "damping": (_number, False), "free_angle": (_number, False),
                              "torque": (_law, False)},
        "controller": {"joint": (_string, True), "target": (_law, True),
                       "kp": (_number, False), "kd": (_number, False),
                       "feedforward": (_law, False), "max_effort": (_number, False),
                       "no_load_speed": (_number, False)},
        "ground-contact": {"body": (_string, True), "point": (_point(dimension), False),
                           "normal": (_vector(dimension), False),
                           "surface_point": (_vector(dimension), False),
                           "restitution": (_number, False), "mu": (_number, False),
                           "armed_ahead_of": (_string, False),
                           "forward": (_vector(dimension), False)},
    }
    return FORCE_TYPES[kind], {"name": (_string, True), "type": (_string, True),
                               **schemas[kind]}


def _steps(value) -> tuple:
    """The ground's steps: a list of ``[at, rise]`` pairs, possibly empty."""
    return tuple(tuple(_vector(2)(s)) for s in (value if isinstance(value, list) else [value]))


#: keys of the [ground] table
_GROUND_KEYS = {"policy": (_string, False), "mu": (_number, False), "faces": (_integer, False),
                "min_normal": (_number, False), "default_reference": (_number, False),
                "reference_efforts": (_constants, False), "slope": (_number, False),
                "heading": (_number, False), "steps": (_steps, False)}


def _driver_kind(table: dict) -> str:
    """Drivers may state their type; otherwise a ``joint`` key makes a joint driver."""
    kind = table.get("type")
    return kind if isinstance(kind, str) else ("joint" if "joint" in table else "coordinate")


# ------------------------------------------------------------------ the reader

_SECTIONS = ("scene", "ground", "body", "joint", "driver", "force")
_TABLES = ("scene", "ground")  # sections written as one table, the others as arrays of tables


class _Reader:
    def __init__(self, path: Path):
        self.path = path
        self.problems: list[Problem] = []
        self.failed: set[str] = set()  # names of elements that could not be built

    def where(self, key: str) -> str:
        return f"{self.path}, {key}"

    def add(self, element: str, key: str, message: str) -> None:
        self.problems.append(Problem(element, message, self.where(key)))

    def read(self, document: dict) -> Scene:
        for key in document:
            if key not in _SECTIONS:
                self.add("file", _key(key), f"unknown section {_shown(key)} (expected "
                         + ", ".join(f"[{s}]" if s in _TABLES else f"[[{s}]]"
                                     for s in _SECTIONS) + ")")
        scene = self._scene(document.get("scene", {}))
        scene.ground = self._ground(document.get("ground", {}))
        dim = scene.dimension
        sections = {
            "body": (lambda t: t.get("type", "spatial" if dim == 3 else "planar"),
                     ("spatial", "planar", "particle"), _body_schema),
            "joint": (lambda t: t.get("type"), tuple(JOINT_TYPES), _joint_schema),
            "driver": (_driver_kind, tuple(DRIVER_TYPES), _driver_schema),
            "force": (lambda t: t.get("type"), tuple(FORCE_TYPES), _force_schema),
        }
        for section, (kind_of, kinds, schema) in sections.items():
            entries = document.get(section, [])
            if not isinstance(entries, list):
                self.add("file", section, f"must be an array of tables, written [[{section}]]")
                continue
            for i, table in enumerate(entries):
                key = f"{section}[{i}]"
                if not isinstance(table, dict):
                    self.add(section, key, "must be a table")
                    continue
                name = table.get("name")
                kind = kind_of(table)
                label = f"{section} {quoted(name if isinstance(name, str) else f'#{i}')}"
                if not isinstance(kind, str) or kind not in kinds:
                    self.add(label, f"{key}.type",
                             f"type must be one of {', '.join(kinds)}, got {_shown(kind)}")
                    self.failed.add(str(name))
                    continue
                label += f" ({kind})" if kind != section else ""
                element = self._element(table, key, label, dim, *schema(kind, dim))
                if element is not None:
                    element.source = self.where(key)
                    scene.add(element)
        return scene

    def _scene(self, table) -> Scene:
        if not isinstance(table, dict):
            self.add("scene", "scene", "must be a table, written [scene]")
            table = {}
        spec = {"name": (_string, False), "dimension": (_integer, False),
                "length_unit": (_string, False), "gravity": (_vector((2, 3)), False),
                "characteristic_length": (_number, False), "report_forces": (_boolean, False)}
        values = self._convert(table, "scene", "scene", spec)
        values.setdefault("name", self.path.stem)
        dimension = values.get("dimension", 3)
        if dimension not in (2, 3):
            self.add("scene", "scene.dimension", f"must be 2 or 3, got {dimension}")
            values["dimension"] = 3
        return Scene(**values, source=str(self.path))

    def _ground(self, table) -> GroundForces:
        """The ground-force settings; their values are checked with the scene's."""
        if not isinstance(table, dict):
            self.add("ground", "ground", "must be a table, written [ground]")
            table = {}
        values = self._convert(table, "ground", "ground", _GROUND_KEYS)
        return GroundForces(**values, source=self.where("ground"))

    def _convert(self, table: dict, key: str, label: str, spec: dict) -> dict:
        values = {}
        for name, value in table.items():
            if name not in spec:
                self.add(label, f"{key}.{_key(name)}", f"unknown key {_shown(name)} (expected "
                         f"one of {', '.join(k for k in spec if k != 'type')})")
                continue
            try:
                values[name] = spec[name][0](value)
            except ValueError as error:
                sub = f".{_key(error.key)}" if isinstance(error, _Invalid) and error.key else ""
                self.add(label, f"{key}.{name}{sub}", str(error))
        return values

    def _element(self, table: dict, key: str, label: str, dimension: int,
                 cls: type[Element], spec: dict) -> Element | None:
        values = self._convert(table, key, label, spec)
        required = {k for k, (_, needed) in spec.items() if needed}
        missing = sorted(required - set(table))
        for name in missing:
            self.add(label, f"{key}.{name}", f"missing required key '{name}'")
        unreadable = required & (set(table) - set(values))
        if missing or unreadable:
            self.failed.add(str(table.get("name")))
            return None
        values.pop("type", None)
        if cls is Particle and "position" not in values:
            values["position"] = np.zeros(dimension)  # a particle's size follows the scene
        try:
            return cls(**values)
        except (TypeError, ValueError) as error:
            self.add(label, key, str(error))
            self.failed.add(str(table.get("name")))
            return None

    def follow_up(self, problems: list[Problem]) -> list[Problem]:
        """Drop 'unknown body/joint' problems about elements already reported as unreadable."""
        echoes = {f"unknown {kind} '{name}'" for name in self.failed
                  for kind in ("body", "joint")}
        return [p for p in problems if p.message not in echoes]


def read_scene(path: str | Path) -> Scene:
    """Read and validate a TOML scene file (a robot description's: its walking scene).

    Parameters
    ----------
    path : str or Path
        The scene file (docs/scene-format.md).

    Returns
    -------
    Scene

    Raises
    ------
    InputFileError
        The file is missing, unreadable or not valid TOML.
    ModelError
        The file is TOML but describes an invalid scene; lists every problem with its key.
    """
    path = Path(path)
    document = read_toml(path, "scene file")
    if "robot" in document:  # a robot description: its walking scene
        return robot_scene(document, path)
    return scene_from_document(document, path)


def scene_from_document(document: dict, path: str | Path) -> Scene:
    """The scene of a parsed TOML document (what :func:`read_scene` reads from a file);
    ``path`` names it in messages.

    Raises
    ------
    ModelError
        The document describes an invalid scene; lists every problem with its key.
    """
    reader = _Reader(Path(path))
    with np.errstate(all="ignore"):  # huge values overflow in the checks, which report them
        scene = reader.read(document)
        problems = reader.problems + reader.follow_up(scene.problems())
    if problems:
        raise ModelError(f"scene file {Path(path)}", problems)
    return scene
