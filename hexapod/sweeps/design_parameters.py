"""Design parameters named by scene keys (``body.femur.mass``), ``*`` matching any element name.

The keys are those of a study (:func:`hexapod.sweeps.cases.set_scene_key`): a dotted path into
the scene's TOML form. Sensitivities cover the bodies' inertia for now:

* ``body.NAME.mass`` (kg);
* ``body.NAME.inertia``: every component as the scene gives it (3 principal moments or the 6
  entries ``xx yy zz xy xz yz`` of a spatial body, in its ``inertia_rotation`` axes; a planar
  body's one moment), each a parameter ``body.NAME.inertia.K``; ``body.NAME.inertia.K`` names
  one. Values and derivatives are in SI (kg m^2) whatever the scene's length unit, as every
  output (``InertiaChange.scene_scale`` converts to the scene's kg L^2).

A glob that matches bodies without the key (a particle has no inertia) skips them; a name that
matches nothing, or a key sensitivities do not cover, is refused.
"""

from __future__ import annotations

import tomllib
from collections.abc import Sequence
from fnmatch import fnmatchcase
from typing import TYPE_CHECKING

import numpy as np

from hexapod.algorithms.sensitivity import InertiaChange
from hexapod.scene.bodies import Particle, PlanarBody, inertia_tensor
from hexapod.sweeps.cases import StudyError

if TYPE_CHECKING:
    from hexapod.scene.scene import Scene

_COVERED = ("masses and inertias, body.NAME.mass and body.NAME.inertia[.K] ('*' matches any "
            "NAME); lengths, joint positions and the gait's parameters move the motion itself, "
            "whose derivatives are not written yet")


def inertia_parameters(scene: Scene, patterns: Sequence[str],
                       source: str = "--parameters") -> tuple[InertiaChange, ...]:
    """The parameters ``patterns`` name in ``scene``, in the order named, each once.

    Parameters
    ----------
    scene : Scene
    patterns : sequence of str
        Scene keys, ``*`` matching any body name.
    source : str
        What gave them, for the messages.

    Returns
    -------
    tuple of InertiaChange

    Raises
    ------
    StudyError
        A key sensitivities do not cover, a body name that matches nothing, a component that
        does not exist; one message naming ``source`` and the key.
    """
    from hexapod.scene.writer import scene_text

    document = tomllib.loads(scene_text(scene))
    bodies = {b["name"]: b for b in document.get("body", [])}
    found: dict[str, InertiaChange] = {}
    for pattern in patterns:
        parts = pattern.split(".")
        if (parts[0] != "body" or len(parts) not in (3, 4) or parts[2] not in ("mass", "inertia")
                or (len(parts) == 4 and parts[2] != "inertia")):
            raise StudyError(f"{source}: '{pattern}' is not a parameter sensitivities cover: "
                             f"{_COVERED}")
        names = [n for n in bodies if fnmatchcase(n, parts[1])]
        if not names:
            shown = ", ".join(list(bodies)[:8]) + (", ..." if len(bodies) > 8 else "")
            raise StudyError(f"{source}: '{pattern}': no body matches '{parts[1]}' (bodies: "
                             f"{shown or 'none'})")
        glob = len(names) > 1 or names[0] != parts[1]
        for name in names:
            for change in _changes(scene, bodies[name], parts, pattern, source, glob):
                found.setdefault(change.name, change)
    return tuple(found.values())


def _changes(scene, entry: dict, parts: list[str], pattern: str, source: str, glob: bool):
    name, body = entry["name"], scene.bodies[entry["name"]]
    planar = isinstance(body, PlanarBody)
    size = 1 if planar else 3
    if parts[2] == "mass":
        return [InertiaChange(f"body.{name}.mass", name, 1.0, np.zeros((size, size)), "kg",
                              float(entry["mass"]))]
    if isinstance(body, Particle):
        if glob:
            return []
        raise StudyError(f"{source}: '{pattern}': body '{name}' is a particle: it has no inertia")
    unit, to_si = "kg m^2", scene.unit ** 2  # derivatives per SI unit, as every output
    if planar:
        if len(parts) == 4:
            raise StudyError(f"{source}: '{pattern}': the planar body '{name}' has one moment of "
                             f"inertia, body.{name}.inertia")
        return [InertiaChange(f"body.{name}.inertia", name, 0.0, np.ones((1, 1)), unit,
                              float(entry["inertia"]) * to_si, to_si)]
    given = np.asarray(entry["inertia"], dtype=float)
    if given.ndim != 1:
        raise StudyError(f"{source}: '{pattern}': body '{name}' gives its inertia as a 3 x 3 "
                         "matrix; give it as 3 principal moments or 6 entries (xx yy zz xy xz "
                         "yz) to vary its components")
    components = range(given.size)
    if len(parts) == 4:
        if not parts[3].isdigit() or int(parts[3]) >= given.size:
            raise StudyError(f"{source}: '{pattern}': body '{name}' has inertia components 0 "
                             f"to {given.size - 1}")
        components = [int(parts[3])]
    R = body.inertia_rotation
    changes = []
    for k in components:
        unit_entry = np.zeros(given.size)
        unit_entry[k] = 1.0
        changes.append(InertiaChange(f"body.{name}.inertia.{k}", name, 0.0,
                                     R @ inertia_tensor(unit_entry) @ R.T, unit,
                                     float(given[k]) * to_si, to_si))
    return changes
