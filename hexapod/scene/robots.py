"""Robot descriptions read wherever a scene is: a scene file whose document has a ``[robot]``
table (a URDF and how the robot walks) is built by the reader a package registers in the entry
point group ``hexapod.robots`` (the ``legs`` package's), so the engine reads it without importing
that package."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from hexapod.scene.scene import Scene


def robot_scene(document: dict, path: Path) -> Scene:
    """The walking scene of a robot description (a TOML document with a ``[robot]`` table,
    read from ``path``), by the reader a package registers in the entry point group
    ``hexapod.robots`` (the ``legs`` package's).

    Parameters
    ----------
    document : dict
        The parsed file.
    path : Path
        Where it was read from (its URDF is found relative to it).

    Returns
    -------
    Scene

    Raises
    ------
    ModelError
        No package reads robot descriptions, or the description's problems.
    """
    from importlib.metadata import entry_points

    from hexapod.errors import ModelError, Problem

    readers = list(entry_points(group="hexapod.robots"))
    if not readers:
        raise ModelError(f"scene file {path}", [Problem(
            "robot", "is a robot description, which needs a package that reads them (legs, "
            "installed with hexapod)", str(path))])
    return readers[0].load()(document, path)
