"""Scenes by name: the built-in scenes, and the one loader of scene, URDF and built-in models.

Built-in scenes are the entry points of the group ``hexapod.scenes`` (the leg and robot models
of the ``legs`` package register theirs in ``pyproject.toml``), so the engine finds them without
importing ``legs``. This module imports the readers only when it loads a scene, so that the
command line's help names the default scene without loading NumPy or CasADi.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from hexapod.errors import InputFileError

if TYPE_CHECKING:
    from hexapod.scene.scene import Scene

#: The scene of the main job (``hexapod report`` with no SCENE).
DEFAULT_SCENE = "front-leg"


def builtin_scenes() -> dict:
    """The built-in scenes by name.

    Returns
    -------
    dict
        ``{name: importlib.metadata.EntryPoint}``; ``entry_point.load()()`` builds the scene and
        ``entry_point.value`` names its builder.
    """
    from importlib.metadata import entry_points

    return {ep.name: ep for ep in entry_points(group="hexapod.scenes")}


def load_scene(name_or_path: str | Path, *, base: str = "auto") -> Scene:
    """A scene from a URDF (``.urdf``, ``.xml``) or TOML file, or a built-in scene by name.

    Parameters
    ----------
    name_or_path : str or Path
        A file path, or the name of a built-in scene (see :func:`builtin_scenes`).
    base : {"auto", "free", "fixed"}
        A URDF model's root link (:func:`hexapod.scene.urdf.read_urdf`); only ``"auto"`` for
        the other scenes.

    Returns
    -------
    Scene

    Raises
    ------
    InputFileError
        The file cannot be read or is malformed (the message names the file, the element and
        the problem), or there is no such file and no built-in scene of that name.
    """
    path = Path(name_or_path)
    if path.suffix.lower() in (".urdf", ".xml"):
        from hexapod.scene.urdf import read_urdf

        return read_urdf(path, base=base)
    if base != "auto":
        raise InputFileError(f"{name_or_path}: base={base!r} (--base) is for URDF models; a "
                             "scene file or a built-in scene says how its bodies stand")
    if path.suffix == ".toml" or (path.exists() and not path.is_dir()):  # a pipe: refused
        from hexapod.scene.reader import read_scene  # with TOML's parser: not for a URDF

        return read_scene(path)
    scenes = builtin_scenes()
    if str(name_or_path) in scenes:
        return scenes[str(name_or_path)].load()()
    if path.is_dir():
        raise InputFileError(f"{path}: is a directory, not a scene file")
    known = ", ".join(sorted(scenes)) or "none installed"
    raise InputFileError(f"{name_or_path}: no such scene file, and no built-in scene of that "
                         f"name (built-in: {known})")
