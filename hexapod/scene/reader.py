"""Read a scene from a TOML file (the format is described in ``docs/scene-format.md``).

Every problem, from a misspelt key to a non-positive mass, is collected with the file and the key
it was found at, and reported in one :class:`~hexapod.errors.ModelError`. A file that cannot be
read or parsed gives an :class:`~hexapod.errors.InputFileError`.
"""

from __future__ import annotations

import tomllib
from collections.abc import Callable
from pathlib import Path

import numpy as np

from hexapod.errors import InputFileError, ModelError, Problem
from hexapod.scene.bodies import Particle, PlanarBody, SpatialBody
from hexapod.scene.drivers import CoordinateDriver, JointDriver
from hexapod.scene.element import Element
from hexapod.scene.forces import FORCE_TYPES
from hexapod.scene.joints import JOINT_TYPES
from hexapod.scene.laws import LAW_TYPES, Constant, Law
from hexapod.scene.scene import Scene
from hexapod.spatial import (
    Placement,
    rotation_2d,
    rotation_about_axis,
    rotation_from_euler_parameters,
    rotation_from_rpy,
)


class _Invalid(ValueError):
    """A value that cannot be converted; its message says why."""


# ------------------------------------------------------------------ value converters

def _number(value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _Invalid(f"must be a number, got {value!r}")
    return float(value)


def _vector(size: int | tuple[int, ...]):
    sizes = (size,) if isinstance(size, int) else size

    def convert(value) -> np.ndarray:
        if not isinstance(value, list) or len(value) not in sizes:
            raise _Invalid(f"must be a list of {' or '.join(map(str, sizes))} numbers, "
                           f"got {value!r}")
        return np.array([_number(x) for x in value])

    return convert


def _string(value) -> str:
    if not isinstance(value, str):
        raise _Invalid(f"must be a string, got {value!r}")
    return value


def _integer(value) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise _Invalid(f"must be an integer, got {value!r}")
    return value


def _matrix3(value) -> np.ndarray:
    if not (isinstance(value, list) and len(value) == 3
            and all(isinstance(r, list) and len(r) == 3 for r in value)):
        raise _Invalid(f"must be a 3 x 3 matrix (list of 3 lists of 3 numbers), got {value!r}")
    return np.array([[_number(x) for x in row] for row in value])


def _inertia(value):
    if isinstance(value, list) and value and isinstance(value[0], list):
        return _matrix3(value)
    return _vector((3, 6))(value)


def _rotation(dimension: int) -> Callable:
    """A rotation: in space ``{rpy = [...]}``, ``{quaternion = [e0, e1, e2, e3]}``,
    ``{matrix = [[...]]}`` or ``{axis = [...], angle = ...}``; in the plane an angle (rad)."""

    def convert(value):
        if dimension == 2:
            return rotation_2d(_number(value))
        if not isinstance(value, dict) or not value:
            raise _Invalid("must be a table with rpy, quaternion, matrix or axis and angle, "
                           f"got {value!r}")
        keys = set(value)
        try:
            return _table_rotation(value, keys)
        except _Invalid as error:
            raise _Invalid(f"{'/'.join(sorted(keys))}: {error}") from None

    return convert


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
        return _matrix3(value["matrix"])
    if keys == {"axis", "angle"}:
        axis = _vector(3)(value["axis"])
        if not np.all(np.isfinite(axis)) or np.linalg.norm(axis) < 1e-12:
            raise _Invalid("axis must be finite and non-zero")
        return rotation_about_axis(axis, _number(value["angle"]))
    raise _Invalid("give exactly one of rpy, quaternion, matrix, or axis and angle")


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
                raise _Invalid(f"unknown key(s) {', '.join(sorted(unknown))}; a frame has "
                               "position and rotation")
            position = _vector(dimension)(value.get("position", [0.0] * dimension))
            rotation = _rotation(dimension)(value["rotation"]) if "rotation" in value else None
            return Placement(position, rotation)
        raise _Invalid(f"must be a marker name, a point or a table, got {value!r}")

    return convert


def _point(dimension: int) -> Callable:
    def convert(value):
        if isinstance(value, str):
            return value
        return _vector(dimension)(value)

    return convert


def _law(value) -> Law:
    """A number (constant) or a table ``{type = "...", ...}``."""
    if not isinstance(value, dict):
        return Constant(_number(value))
    kind = value.get("type")
    if kind not in LAW_TYPES:
        raise _Invalid(f"law type must be one of {', '.join(LAW_TYPES)}, got {kind!r}")
    fields = {k: v for k, v in value.items() if k != "type"}
    spec = {
        "constant": {"value": _number},
        "polynomial": {"coefficients": _vector(tuple(range(1, 64))), "t0": _number},
        "harmonic": {"offset": _number, "cos": _list_of_numbers, "sin": _list_of_numbers,
                     "frequency": _number, "t0": _number},
        "spline": {"times": _list_of_numbers, "values": _list_of_numbers,
                   "degree": _integer, "boundary": _string},
    }[kind]
    unknown = set(fields) - set(spec)
    if unknown:
        raise _Invalid(f"unknown key(s) {', '.join(sorted(unknown))} for a {kind} law "
                       f"(expected {', '.join(spec)})")
    args = {k: spec[k](v) for k, v in fields.items()}
    law = LAW_TYPES[kind](**{k: tuple(v) if isinstance(v, np.ndarray) else v
                             for k, v in args.items()})
    problems = law.problems()
    if problems:
        raise _Invalid("; ".join(problems))
    return law


def _list_of_numbers(value) -> tuple[float, ...]:
    if not isinstance(value, list):
        raise _Invalid(f"must be a list of numbers, got {value!r}")
    return tuple(_number(x) for x in value)


def _laws(count: tuple[int, ...]) -> Callable:
    def convert(value):
        if not isinstance(value, list) or len(value) not in count:
            raise _Invalid(f"must be a list of {' or '.join(map(str, count))} numbers or laws, "
                           f"got {value!r}")
        return tuple(_law(x) for x in value)

    return convert


def _markers(dimension: int) -> Callable:
    def convert(value):
        if not isinstance(value, dict):
            raise _Invalid(f"must be a table of named frames, got {value!r}")
        frames = {}
        for name, frame in value.items():
            try:
                ref = _frame(dimension)(frame)
            except _Invalid as error:
                raise _Invalid(f"marker '{name}': {error}") from None
            if isinstance(ref, str):
                raise _Invalid(f"marker '{name}' must be a point or a frame, not a name")
            frames[name] = ref
        return frames

    return convert


# ------------------------------------------------------------------ element schemas

def _body_schema(kind: str, dimension: int) -> tuple[type[Element], dict, set]:
    common = {"name": _string, "type": _string, "mass": _number,
              "position": _vector(dimension), "velocity": _vector(dimension),
              "markers": _markers(dimension)}
    if kind == "particle":
        return Particle, common, {"name", "mass"}
    if kind == "planar":
        return PlanarBody, {**common, "inertia": _number, "com": _vector(2), "angle": _number,
                            "angular_velocity": _number}, {"name", "mass", "inertia"}
    return SpatialBody, {**common, "inertia": _inertia, "com": _vector(3),
                         "rotation": _rotation(3), "inertia_rotation": _rotation(3),
                         "angular_velocity": _vector(3)}, {"name", "mass", "inertia"}


def _joint_schema(kind: str, dimension: int) -> tuple[type[Element], dict, set]:
    schema = {"name": _string, "type": _string, "parent": _string, "child": _string,
              "parent_frame": _frame(dimension), "child_frame": _frame(dimension),
              "origin": _vector(dimension), "rotation": _rotation(dimension)}
    if kind == "revolute" and dimension == 3 or kind == "prismatic":
        schema["axis"] = _vector(dimension)
    if kind == "distance":
        schema["length"] = _number
    return JOINT_TYPES[kind], schema, {"name", "parent", "child"}


def _driver_schema(table: dict, dimension: int) -> tuple[type[Element], dict, set]:
    if "joint" in table:
        return JointDriver, {"name": _string, "joint": _string, "law": _law}, {"name", "law"}
    return CoordinateDriver, {"name": _string, "body": _string, "coordinate": _string,
                              "law": _law}, {"name", "body", "coordinate", "law"}


def _force_schema(kind: str, dimension: int) -> tuple[type[Element], dict, set]:
    torque_count = (3,) if dimension == 3 else (1,)
    schemas = {
        "spring": ({"body_a": _string, "body_b": _string, "point_a": _point(dimension),
                    "point_b": _point(dimension), "stiffness": _number, "damping": _number,
                    "free_length": _number, "force": _law}, {"body_a", "body_b"}),
        "applied-force": ({"body": _string, "force": _laws((dimension,)),
                           "point": _point(dimension), "frame": _string}, {"body", "force"}),
        "applied-torque": ({"body": _string, "torque": _laws(torque_count),
                            "frame": _string}, {"body", "torque"}),
        "effort": ({"joint": _string, "law": _law}, {"joint", "law"}),
    }
    schema, required = schemas[kind]
    return FORCE_TYPES[kind], {"name": _string, "type": _string, **schema}, {"name"} | required


# ------------------------------------------------------------------ the reader

_SECTIONS = ("scene", "body", "joint", "driver", "force")


class _Reader:
    def __init__(self, path: Path):
        self.path = path
        self.problems: list[Problem] = []
        self.failed: set[str] = set()  # names of elements that could not be converted

    def where(self, key: str) -> str:
        return f"{self.path}, {key}"

    def add(self, element: str, key: str, message: str) -> None:
        self.problems.append(Problem(element, message, self.where(key)))

    def read(self, document: dict) -> Scene:
        for key in document:
            if key not in _SECTIONS:
                self.add("file", key, f"unknown section '{key}' (expected "
                         + ", ".join(f"[{s}]" if s == "scene" else f"[[{s}]]"
                                     for s in _SECTIONS) + ")")
        scene = self._scene(document.get("scene", {}))
        tables = {
            "body": lambda t: _body_schema(
                t.get("type", "spatial" if scene.dimension == 3 else "planar"), scene.dimension),
            "joint": lambda t: _joint_schema(t.get("type"), scene.dimension),
            "driver": lambda t: _driver_schema(t, scene.dimension),
            "force": lambda t: _force_schema(t.get("type"), scene.dimension),
        }
        kinds = {"body": ("spatial", "planar", "particle"), "joint": tuple(JOINT_TYPES),
                 "force": tuple(FORCE_TYPES)}
        for section, schema in tables.items():
            entries = document.get(section, [])
            if not isinstance(entries, list):
                self.add("file", section, f"must be an array of tables, written [[{section}]]")
                continue
            for i, table in enumerate(entries):
                key = f"{section}[{i}]"
                if not isinstance(table, dict):
                    self.add(section, key, "must be a table")
                    continue
                label = f"{section} '{table.get('name', f'#{i}')}'"
                if section in kinds:
                    default = "spatial" if scene.dimension == 3 else "planar"
                    kind = table.get("type", default if section == "body" else None)
                    if kind not in kinds[section]:
                        self.add(label, f"{key}.type", f"type must be one of "
                                 f"{', '.join(kinds[section])}, got {kind!r}")
                        self.failed.add(str(table.get("name")))
                        continue
                element = self._element(table, key, label, *schema(table))
                if element is not None:
                    element.source = self.where(key)
                    scene.add(element)
        return scene

    def _scene(self, table) -> Scene:
        if not isinstance(table, dict):
            self.add("scene", "scene", "must be a table, written [scene]")
            table = {}
        spec = {"name": _string, "dimension": _integer, "length_unit": _string,
                "gravity": _vector((2, 3)), "characteristic_length": _number}
        values = self._convert(table, "scene", "scene", spec)
        values.setdefault("name", self.path.stem)
        dimension = values.get("dimension", 3)
        if dimension not in (2, 3):
            self.add("scene", "scene.dimension", f"must be 2 or 3, got {dimension}")
            values["dimension"] = 3
        return Scene(**values, source=str(self.path))

    def _convert(self, table: dict, key: str, label: str, spec: dict) -> dict:
        values = {}
        for name, value in table.items():
            if name not in spec:
                self.add(label, f"{key}.{name}", f"unknown key '{name}' (expected one of "
                         f"{', '.join(k for k in spec if k != 'type')})")
                continue
            try:
                values[name] = spec[name](value)
            except _Invalid as error:
                self.add(label, f"{key}.{name}", str(error))
            except ValueError as error:
                self.add(label, f"{key}.{name}", str(error))
        return values

    def _element(self, table: dict, key: str, label: str, cls: type[Element], spec: dict,
                 required: set) -> Element | None:
        values = self._convert(table, key, label, spec)
        count = len(self.problems)
        bad_values = len(values) < len(set(table) & set(spec))
        for name in sorted(required - set(table)):
            self.add(label, f"{key}.{name}", f"missing required key '{name}'")
        # unknown keys are reported but do not stop the element's own checks
        if bad_values or len(self.problems) > count:
            self.failed.add(str(table.get("name")))
            return None
        values.pop("type", None)
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
    """Read and validate a TOML scene file.

    Raises
    ------
    InputFileError
        The file is missing, unreadable or not valid TOML.
    ModelError
        The file is TOML but describes an invalid scene; lists every problem with its key.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputFileError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError) as error:
        raise InputFileError(f"{path}: cannot read the file ({error})") from None
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise InputFileError(f"{path}: not valid TOML: {error}") from None
    reader = _Reader(path)
    scene = reader.read(document)
    problems = reader.problems + reader.follow_up(scene.problems())
    if problems:
        raise ModelError(f"scene file {path}", problems)
    return scene

