"""Write a scene as a TOML file that :func:`hexapod.scene.reader.read_scene` reads back.

The scene is validated first, so that every file written reads back as the same scene: names
follow the rules the reader applies (:func:`hexapod.scene.element.name_problem`,
:func:`~hexapod.scene.element.line_problem`), and every string is written with TOML's escapes
(quotes, backslashes, control characters). Only text no UTF-8 file can hold (a lone surrogate,
in a mesh path, say) is refused, naming the element and the key. Values equal to their defaults
are left out; numbers are written as Python's shortest repr, which reads back to the same bits;
rotations are written as ``rpy`` (URDF's convention) (pitch from atan2, exact to round-off even
near +-90 degrees); the file is written atomically (a temporary file renamed), so a failure
leaves no partial file.
"""

from __future__ import annotations

import dataclasses
import re
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from hexapod._support.files import write_atomically
from hexapod.errors import HexapodError, ModelError
from hexapod.scene.bodies import Body
from hexapod.scene.contacts import GroundForces
from hexapod.scene.element import Element, character, quoted
from hexapod.scene.forces import ForceElement
from hexapod.scene.joints import Joint
from hexapod.scene.laws import Constant, Law, Scaled
from hexapod.scene.scene import Scene
from hexapod.spatial import Placement, rpy_from_rotation


def _number(x: float) -> str:
    return repr(float(x))


def _array(values) -> str:
    values = np.asarray(values, dtype=float)
    if values.ndim == 2:
        return "[" + ", ".join(_array(row) for row in values) + "]"
    return "[" + ", ".join(_number(x) for x in values) + "]"


class _Unwritable(ValueError):
    """Text that no TOML file can hold; the message grows the place it was found at."""


@contextmanager
def _at(where: str):
    try:
        yield
    except _Unwritable as error:
        raise _Unwritable(f"{where}: {error}") from None


#: TOML's escapes in a basic string: its short ones, and \uXXXX for the other control characters
_ESCAPES = {**{c: f"\\u{c:04X}" for c in (*range(0x20), 0x7F)},
            **{ord(c): e for c, e in (("\\", "\\\\"), ('"', '\\"'), ("\b", "\\b"),
                                      ("\t", "\\t"), ("\n", "\\n"), ("\f", "\\f"),
                                      ("\r", "\\r"))}}
_SURROGATE = re.compile(r"[\ud800-\udfff]")


def _unwritable(text: str) -> str:
    """Why ``text`` cannot be written in a UTF-8 file (empty when it can)."""
    bad = _SURROGATE.search(text)
    return (f"holds {character(bad.group())}, a lone surrogate, which no UTF-8 file can hold"
            if bad else "")


def _string(text: str) -> str:
    """A TOML basic string, every character the format forbids as it is escaped."""
    why = _unwritable(text)
    if why:
        raise _Unwritable(why)
    return '"' + text.translate(_ESCAPES) + '"'


def _table_key(name: str) -> str:
    """A key of a TOML table: bare when TOML allows it, else a quoted string."""
    return name if re.fullmatch(r"[A-Za-z0-9_-]+", name) else _string(name)


def _rotation(R: np.ndarray) -> str:
    R = np.asarray(R, dtype=float)
    if R.shape == (2, 2):
        return _number(np.arctan2(R[1, 0], R[0, 0]))
    return f"{{ rpy = {_array(rpy_from_rotation(R))} }}"


def _frame(frame) -> str:
    if isinstance(frame, str):
        return _string(frame)
    parts = [f"position = {_array(frame.position)}"]
    if not np.allclose(frame.rotation, np.eye(frame.dimension), rtol=0, atol=0):
        parts.append(f"rotation = {_rotation(frame.rotation)}")
    return "{ " + ", ".join(parts) + " }"


def _law(law: Law) -> str:
    if isinstance(law, Scaled):
        return _law(law.law.scaled(law.factor))
    if isinstance(law, Constant):
        return _number(law.value)
    parts = [f'type = "{law.kind}"']
    for f in dataclasses.fields(law):
        if f.name.startswith("_"):
            continue
        value = getattr(law, f.name)
        if value is None:  # an optional key left out
            continue
        if isinstance(value, tuple) and value and isinstance(value[0], tuple):
            # (name, number) pairs, an expression law's constants: a table
            parts.append(f"{f.name} = {{ " + ", ".join(
                f"{_table_key(name)} = {_number(number)}" for name, number in value) + " }")
        elif isinstance(value, (tuple, np.ndarray)):
            if len(value):
                parts.append(f"{f.name} = {_array(value)}")
        elif isinstance(value, str):
            parts.append(f"{f.name} = {_string(value)}")
        elif isinstance(value, bool):
            parts.append(f"{f.name} = {'true' if value else 'false'}")
        elif isinstance(value, int):
            parts.append(f"{f.name} = {value}")
        else:
            parts.append(f"{f.name} = {_number(value)}")
    return "{ " + ", ".join(parts) + " }"


def _inertia(J: np.ndarray) -> str:
    J = np.asarray(J, dtype=float)
    if np.count_nonzero(J - np.diag(np.diag(J))) == 0:
        return _array(np.diag(J))
    return _array([J[0, 0], J[1, 1], J[2, 2], J[0, 1], J[0, 2], J[1, 2]])


def _is_default(name: str, value) -> bool:
    if value is None:
        return True
    if name in ("com", "position", "velocity", "angular_velocity", "angle", "damping", "stiffness",
                "free_angle", "advance", "turn", "centre") and np.all(
                    np.asarray(value, dtype=float) == 0):
        return True
    if name in ("rotation", "inertia_rotation") and np.array_equal(
            np.asarray(value), np.eye(np.asarray(value).shape[0])):
        return True
    if name == "guide":
        return value is False
    return name == "frame" and value == "world"


def _value(name: str, value) -> str:
    if name in ("rotation", "inertia_rotation"):
        return _rotation(value)
    if name == "inertia":
        return _number(value) if np.ndim(value) == 0 else _inertia(value)
    if name in ("parent_frame", "child_frame"):
        return _frame(value)
    if name == "markers":
        return "{ " + ", ".join(f"{_string(k)} = {_frame(v)}" for k, v in value.items()) + " }"
    if isinstance(value, Law):
        return _law(value)
    if isinstance(value, tuple) and value and all(isinstance(x, str) for x in value):
        return "[" + ", ".join(_string(x) for x in value) + "]"  # a posture's joints
    if isinstance(value, tuple):  # force and torque components
        return "[" + ", ".join(_law(law) for law in value) + "]"
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, Placement):
        return _frame(value)
    if np.ndim(value) >= 1:
        return _array(value)
    return _number(value)


#: the fields every joint's table holds (the others: the type's file keys)
_JOINT_KEYS = frozenset(f.name for f in dataclasses.fields(Joint))


def _section(element: Element) -> str:
    if isinstance(element, Body):
        return "body"
    if isinstance(element, Joint):
        return "joint"
    if getattr(element, "family", None) == "driver":
        return "driver"
    assert isinstance(element, ForceElement)
    return "force"


def _table(element: Element, dimension: int) -> list[str]:
    lines = [f"[[{_section(element)}]]", f"name = {_string(element.name)}",
             f'type = "{element.kind}"']
    for f in dataclasses.fields(element):
        if f.name in ("name", "source") or f.name.startswith("_"):
            continue
        if isinstance(element, Joint) and f.name not in _JOINT_KEYS and (
                f.name not in element.file_keys(dimension)):
            continue  # what the type's file does not hold (a planar revolute's axis)
        value = getattr(element, f.name)
        if _is_default(f.name, value) or (f.name in ("markers", "mesh") and not value):
            continue
        with _at(f"{element.label}, {f.name}"):
            lines.append(f"{f.name} = {_value(f.name, value)}")
    return lines


def _setting(value) -> str:
    if isinstance(value, str):
        return _string(value)
    if isinstance(value, int):  # faces; an integer as TOML writes it
        return str(value)
    return _number(value)


def _ground(ground: GroundForces) -> list[str]:
    """The ``[ground]`` settings that differ from the defaults (no lines when none does)."""
    default = GroundForces()
    with _at("ground"):
        settings = [f"{key} = {_setting(getattr(ground, key))}"
                    for key in ("policy", "mu", "faces", "min_normal", "default_reference",
                                "slope", "heading")
                    if getattr(ground, key) != getattr(default, key)]
        if ground.steps:
            settings.append(f"steps = [{', '.join(_array(step) for step in ground.steps)}]")
    lines = ["", "[ground]", *settings] if settings else []
    if ground.reference_efforts:
        lines += ["", "[ground.reference_efforts]"] + [
            f"{_string(joint)} = {_number(value)}"
            for joint, value in ground.reference_efforts.items()]
    return lines


def _comments(header: str) -> list[str]:
    """``header`` as TOML comments, one per line (a comment holds no control character but
    tab)."""
    lines = []
    for number, line in enumerate(header.splitlines(), 1):
        bad = next((c for c in line if (c < " " and c != "\t") or c == "\x7f"), None)
        why = (f"holds {character(bad)}, which a TOML comment cannot hold" if bad
               else _unwritable(line))
        if why:
            raise _Unwritable(f"header, line {number}: {why}")
        lines.append(f"# {line}" if line else "#")
    return lines


def scene_text(scene: Scene, header: str = "") -> str:
    """The TOML text of ``scene``, which :func:`~hexapod.scene.reader.read_scene` reads back
    as the same scene; ``header`` becomes a comment at the top.

    Parameters
    ----------
    scene : Scene
    header : str
        Lines of comment above the scene (empty: none).

    Returns
    -------
    str

    Raises
    ------
    ModelError
        The scene is invalid (every problem listed): it would not read back.
    HexapodError
        A string of the scene (or a line of the header) holds a character no TOML file can hold.
    """
    with np.errstate(all="ignore"):  # huge values overflow in the checks, which report them
        scene.validate()
    try:
        return _text(scene, header)
    except _Unwritable as error:
        raise HexapodError(f"scene {quoted(scene.name)} cannot be written: {error}") from None


def _text(scene: Scene, header: str) -> str:
    lines = _comments(header)
    with _at("scene.name"):
        lines += ["[scene]", f"name = {_string(scene.name)}"]
    lines += [f"dimension = {scene.dimension}", f"length_unit = {_string(scene.length_unit)}",
              f"gravity = {_array(scene.gravity)}"]
    if scene.characteristic_length is not None:
        lines.append(f"characteristic_length = {_number(scene.characteristic_length)}")
    if scene.report_forces:
        lines.append("report_forces = true")
    lines += _ground(scene.ground)
    for element in scene.elements:
        lines += [""] + _table(element, scene.dimension)
    return "\n".join(lines) + "\n"


def write_scene(scene: Scene, path: str | Path, header: str = "") -> Path:
    """Write ``scene`` to ``path`` atomically; ``header`` becomes a comment at the top.

    Parameters
    ----------
    scene : Scene
    path : str or Path
        The TOML file to write (replaced whole, or left untouched on failure).
    header : str
        Lines of comment above the scene (empty: none).

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    ModelError, HexapodError
        The scene cannot be written (see :func:`scene_text`); no file is written.
    InputFileError
        The file cannot be written (the target is left untouched).
    """
    try:
        text = scene_text(scene, header)
    except ModelError as error:
        raise ModelError(f"{path}: not written: {error.subject}", error.problems) from None
    except HexapodError as error:
        raise HexapodError(f"{path}: not written: {error}") from None
    return write_atomically(path, text)
