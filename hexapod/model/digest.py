"""The content hash of a model: a SHA-256 of everything its CasADi Functions are built from.

:func:`hexapod.assemble` builds a model from the scene in SI units alone, so the hash is taken
over that scene's canonical description: the dimension, gravity and settings, and every element
in order (its type and every field, numbers written exactly; dictionaries by sorted keys, so
the order they were filled in does not count), without where each was written (``source``),
without the joints' ranges (``limits``: checked against the results, in no Function) and
without the scene's name. A time law enters the Functions as an input (its values ``w, wd,
wdd`` at each sample), so only its place counts, not its type or numbers: another motion of the
same robot has the same hash. A constant law is folded into the expressions as a number, so its
value counts.

The hash is the same in every process and on every machine for the same description, and
changes with any number, name, element or order that could change the generated code. It is
``Model.digest``; the cache (:mod:`hexapod._support.compiled`) adds hexapod's and CasADi's
versions and the compiler's flags to it. A kernel whose expressions also hold the laws themselves
(``Law.symbolic``) adds :func:`describe` of those laws (``time_laws=True``) to its key.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json

import numpy as np

from hexapod.scene.joints import Joint
from hexapod.scene.laws import Constant, Law
from hexapod.scene.scene import Scene
from hexapod.spatial import Placement

#: The version of the description: changed when what it holds changes.
FORMAT = 1
#: Fields that say where an element was written, not what it is.
_WHERE = frozenset({"source"})
#: A joint's fields that no Function is built from: its range, which the inverse dynamics
#: checks its results against (another range compiles nothing again).
_CHECKED_ONLY = frozenset({"limits"})


def scene_digest(scene: Scene, rank_tolerance: float) -> str:
    """The content hash (64 hexadecimal digits) of the model :func:`hexapod.assemble` builds
    from ``scene`` (in SI units, as assembly sees it) with ``rank_tolerance``; empty when an
    element holds a value :func:`describe` does not know (an element class of the user's):
    such a model is built in each process, never taken from the cache."""
    try:
        return _digest(scene, rank_tolerance)
    except TypeError:
        return ""


def _digest(scene: Scene, rank_tolerance: float) -> str:
    description = {
        "format": FORMAT,
        "dimension": scene.dimension,
        "length_unit": scene.length_unit,
        "gravity": describe(scene.gravity),
        "characteristic_length": describe(scene.characteristic_length),
        "report_forces": scene.report_forces,
        "ground": describe(scene.ground),
        "rank_tolerance": describe(rank_tolerance),
        "elements": [describe(element) for element in scene.elements],
    }
    text = json.dumps(description, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def describe(value, *, time_laws: bool = False):
    """``value`` as plain JSON data that says everything about it: elements, laws, placements,
    arrays, dictionaries, lists and scalars. A time law is ``"time law"`` (a model's input),
    or with ``time_laws`` its full description; a constant law its value.

    Raises
    ------
    TypeError
        For a value of a kind it does not know (rather than a description that would differ
        between processes, as a default ``repr`` with an address would).
    """
    if isinstance(value, Law):
        if isinstance(value, Constant):
            return {"constant": _number(value.value)}
        if not time_laws:
            return "time law"
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return _number(value)
    if isinstance(value, np.ndarray):
        return {"shape": list(value.shape),
                "values": [describe(x) for x in value.reshape(-1).tolist()]}
    if isinstance(value, Placement):
        return {"position": describe(value.position), "rotation": describe(value.rotation)}
    if isinstance(value, dict):
        return {str(k): describe(v, time_laws=time_laws) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [describe(v, time_laws=time_laws) for v in value]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        left_out = _WHERE | _CHECKED_ONLY if isinstance(value, Joint) else _WHERE
        fields = {f.name: describe(getattr(value, f.name), time_laws=time_laws)
                  for f in dataclasses.fields(value) if f.name not in left_out}
        return {"type": f"{type(value).__module__}.{type(value).__qualname__}", **fields}
    raise TypeError(f"cannot describe a {type(value).__name__} for a model's content hash")


def _number(value) -> str | float:
    """A float exactly (``repr`` round-trips); non-finite ones as text, which JSON lacks."""
    value = float(value)
    return value if np.isfinite(value) else repr(value)
