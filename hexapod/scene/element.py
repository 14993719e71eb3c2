"""What every scene element shares: a name, where it was written, and self-checks."""

from __future__ import annotations

import copy
import re
import string
import unicodedata
from dataclasses import dataclass

import numpy as np

from hexapod.errors import Problem
from hexapod.spatial import Placement, is_rotation

#: The name of the fixed frame; not a body, always present.
GROUND = "ground"


@dataclass(frozen=True)
class Attachment:
    """How a sub-model is attached: names get ``prefix + "/"``; its ground becomes ``base``.

    ``transform`` maps the sub-model's world frame into the scene's world frame at the initial
    pose (base pose composed with ``placement``); ``placement`` is the sub-model's world frame in
    the base body's reference frame.
    """

    prefix: str
    base: str
    placement: Placement
    transform: Placement

    def name(self, name: str) -> str:
        return f"{self.prefix}/{name}"

    def body(self, name: str) -> str:
        return self.base if name == GROUND else self.name(name)


def quoted(name) -> str:
    """A name as messages show it: in quotes, or as its shortened repr when it is not a short
    printable string (a name with a line break must not break the one-line message)."""
    if isinstance(name, str) and name.isprintable() and len(name) <= 60:
        return f"'{name}'"
    text = repr(name)
    return text if len(text) <= 60 else text[:57] + "..."


def character(c: str) -> str:
    """One character as a message names it: quoted, and by its code point, e.g. ``'\\n'
    (U+000A)``."""
    return f"{c!r} (U+{ord(c):04X})"


# ------------------------------------------------------------------ the rules for names

#: what an element or marker name may hold (the scene file's keys and messages rely on it)
NAME_RULE = "letters, digits, '_', '-' and '.', in parts joined by '/'"
_NAME = re.compile(r"[A-Za-z0-9_.\-]+(/[A-Za-z0-9_.\-]+)*")
_NAME_CHARACTERS = frozenset(string.ascii_letters + string.digits + "_.-/")
#: Unicode categories a one-line text may not hold: control characters, lone surrogates (no
#: UTF-8 file can hold them), line and paragraph separators
_NOT_IN_A_LINE = ("Cc", "Cs", "Zl", "Zp")


def name_problem(name) -> str:
    """Why ``name`` is not a valid element or marker name, e.g. ``"it holds ' ' (U+0020); ..."``
    (empty when it is valid)."""
    if not isinstance(name, str):
        return "it is not a string"
    if _NAME.fullmatch(name):
        return ""
    if not name:
        return "it is empty"
    bad = next((c for c in name if c not in _NAME_CHARACTERS), None)
    if bad is not None:
        return f"it holds {character(bad)}; a name holds {NAME_RULE}"
    return f"it has an empty part; a name holds {NAME_RULE}"


def line_problem(text) -> str:
    """Why ``text`` is not one non-empty line of text (a scene name), empty when it is."""
    if not isinstance(text, str):
        return "it is not a string"
    if not text:
        return "it is empty"
    bad = next((c for c in text if unicodedata.category(c) in _NOT_IN_A_LINE), None)
    if bad is not None:
        return f"it holds {character(bad)}; a scene name is one line without control characters"
    return ""


class Element:
    """Base of bodies, joints, drivers and force elements.

    Subclasses are dataclasses with a ``name`` and a ``source`` (where the element was written,
    e.g. ``"leg.toml, joint[2]"``; empty for elements built in Python).
    """

    #: element family used in messages, e.g. "body", "joint"
    family: str = "element"
    #: type name used in scene files, e.g. "revolute"
    kind: str = ""

    name: str
    source: str

    @property
    def label(self) -> str:
        kind = f" ({self.kind})" if self.kind and self.kind != self.family else ""
        return f"{self.family} {quoted(self.name)}{kind}"

    def problem(self, key: str, message: str) -> Problem:
        where = f"{self.source}.{key}" if self.source else key
        return Problem(self.label, message, where)

    def problems(self) -> list[Problem]:
        """Problems of the element's own numbers (references are checked by the scene)."""
        return []

    def scaled(self, length: float) -> Element:
        """A copy with every length multiplied by ``length`` (unit conversion)."""
        return copy.copy(self)

    def attached(self, attachment: Attachment) -> Element:
        """A copy renamed and placed for :meth:`Scene.attach`."""
        out = copy.copy(self)
        out.name = attachment.name(self.name)
        return out

    def replace(self, **changes) -> Element:
        out = copy.copy(self)
        for key, value in changes.items():
            setattr(out, key, value)
        return out


# ------------------------------------------------------------------ checks shared by elements

def vector(value, size: int | tuple[int, ...], default=None) -> np.ndarray | None:
    """``value`` as a float array of the given size (None stays None unless a default is given)."""
    if value is None:
        return None if default is None else np.array(default, dtype=float)
    array = np.array(value, dtype=float)
    sizes = (size,) if isinstance(size, int) else size
    if array.ndim != 1 or array.size not in sizes:
        shown = array.tolist() if isinstance(value, np.ndarray) else value
        raise ValueError(f"expected {' or '.join(map(str, sizes))} numbers, got {shown!r}")
    return array


def check_finite(element: Element, key: str, value, out: list[Problem]) -> bool:
    if value is None:
        return True
    array = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(array)):
        out.append(element.problem(key, f"must be finite, got {np.array2string(array)}"))
        return False
    return True


def check_frame(element: Element, key: str, frame, out: list[Problem]) -> None:
    """A frame reference: None, a marker name, or a Placement with finite numbers."""
    if frame is None or isinstance(frame, str):
        return
    if not isinstance(frame, Placement):
        out.append(element.problem(key, f"must be a marker name or a placement, got {frame!r}"))
        return
    if check_finite(element, key + ".position", frame.position, out) and not is_rotation(
        frame.rotation
    ):
        out.append(element.problem(key + ".rotation", "is not a proper rotation matrix"))


def check_axis(element: Element, key: str, axis, out: list[Problem]) -> None:
    if check_finite(element, key, axis, out) and np.linalg.norm(axis) < 1e-12:
        out.append(element.problem(key, "has zero length"))


def scaled_ref(ref, length: float):
    """Scale a point or frame reference (marker names are scaled with their body)."""
    if ref is None or isinstance(ref, str):
        return ref
    if isinstance(ref, Placement):
        return ref.scaled(length)
    return np.asarray(ref, dtype=float) * length


def ground_ref(ref, body: str, attachment: Attachment):
    """A reference given on ``body``; if that is the sub-model's ground, re-express it in the
    base body's reference frame (marker names need no change)."""
    if body != GROUND or ref is None or isinstance(ref, str):
        return ref
    if isinstance(ref, Placement):
        return attachment.placement @ ref
    return attachment.placement.transform_point(ref)
