"""The law classes by the ``type`` of scene files."""

from __future__ import annotations

from functools import cache

from hexapod.scene.laws.base import Constant, Law
from hexapod.scene.laws.closed_form import Harmonic, Polynomial
from hexapod.scene.laws.expression import Expression
from hexapod.scene.laws.gait import Gait
from hexapod.scene.laws.guided import Guided
from hexapod.scene.laws.tabulated import Hermite, Spline

#: Law classes by the ``type`` used in scene files.
LAW_TYPES: dict[str, type[Law]] = {
    cls.kind: cls for cls in (Constant, Polynomial, Harmonic, Spline, Hermite, Gait,
                              Expression, Guided)
}


@cache
def law_types() -> dict[str, type[Law]]:
    """The law classes by the ``type`` of scene files: the engine's (:data:`LAW_TYPES`), and
    those installed packages register in the entry-point group ``hexapod.laws`` (the ``legs``
    package registers its exact gait laws there), so that a scene written with them reads
    back. Looked up once per process (a scene file has a law per driver)."""
    from importlib.metadata import entry_points

    out = dict(LAW_TYPES)
    for entry in entry_points(group="hexapod.laws"):
        if entry.name not in out:
            out[entry.name] = entry.load()
    return out
