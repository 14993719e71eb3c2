"""A cache key is everything that changes a result: for each path whose Functions the cache
keeps (the tree path compiled, the phase path compiled), a scene is run with the cache on, one
of its values is edited (a law's coefficient, a mass, a joint axis, gravity), and the edited
scene's run with the same cache must give the numbers of a run without any cache, and not the
unedited scene's.

The reference is the interpreted run without a cache: compiled C and CasADi's virtual machine
agree to round-off (1e-12 relative here), while every edit moves the efforts by more than 1e-3
relative, so a result served for the unedited scene fails the test by nine orders of magnitude.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

import hexapod as hx
from hexapod._support import compiled as compiled_module
from hexapod._support.compiled import compiler
from hexapod.scene.reader import scene_from_document

pytestmark = pytest.mark.skipif(compiler() is None, reason="no C compiler: nothing is cached")

ROOT = Path(__file__).resolve().parents[1]
TIMES = np.linspace(0.0, 1.0, 21)

#: An open chain, every joint driven: the tree path.
CHAIN = """
[scene]
name = "driven-chain"
dimension = 3
gravity = [0.0, 0.0, -9.81]

[[body]]
name = "upper"
mass = 1.0
inertia = [0.01, 0.08, 0.08]
position = [0.25, 0.0, 0.0]

[[body]]
name = "lower"
mass = 0.5
inertia = [0.005, 0.03, 0.03]
position = [0.7, 0.0, 0.0]

[[joint]]
name = "hip"
type = "revolute"
parent = "ground"
child = "upper"
origin = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]

[[joint]]
name = "knee"
type = "revolute"
parent = "upper"
child = "lower"
origin = [0.5, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]

[[driver]]
name = "hip-motor"
joint = "hip"
law = { type = "harmonic", offset = 0.1, sin = [0.5], frequency = 0.5 }

[[driver]]
name = "knee-motor"
joint = "knee"
law = { type = "harmonic", offset = 0.3, sin = [0.4], frequency = 1.0 }
"""

FOUR_BAR = (ROOT / "data" / "scenes" / "four_bar_3d.toml").read_text()

#: (scene, method, {edit: (text, replacement, count)}): each edit changes one kind of value.
PATHS = {
    "tree": (CHAIN, "tree", {
        "law coefficient": ("sin = [0.5]", "sin = [0.2]", 1),
        "mass": ("mass = 0.5", "mass = 0.9", 1),
        "joint axis": ("axis = [0.0, 0.0, 1.0]", "axis = [1.0, 0.0, 0.0]", 1),
        "gravity": ("gravity = [0.0, 0.0, -9.81]", "gravity = [0.0, -9.81, 0.0]", 1),
    }),
    "phase": (FOUR_BAR, "phase", {
        "law coefficient": ("sin = [0.5]", "sin = [0.2]", 1),
        "mass": ("mass = 1.0", "mass = 2.5", 1),
        # every axis turned over: the crank turns the other way, the loop stays closed
        "joint axis": ("\naxis = [0.0, 0.0, 1.0]", "\naxis = [0.0, 0.0, -1.0]", 4),
        "gravity": ("gravity = [0.0, -9.81, 0.0]", "gravity = [-9.81, 0.0, 0.0]", 1),
    }),
}
CASES = [(path, edit) for path, (_, _, edits) in PATHS.items() for edit in edits]


def _efforts(text: str, method: str, **setting) -> np.ndarray:
    with hx.executing(**setting):
        scene = scene_from_document(tomllib.loads(text), "edited.toml")
        result = hx.inverse_dynamics(hx.assemble(scene), TIMES, method=method)
    assert result.method == method
    return np.concatenate([result.effort.ravel(), result.force.ravel(),
                           result.torque.ravel()])


@pytest.fixture(scope="module")
def filled(tmp_path_factory) -> dict[str, tuple[Path, np.ndarray]]:
    """Per path: a cache folder holding the unedited scene's compiled Functions, and that
    scene's numbers."""
    out = {}
    for path, (text, method, _) in PATHS.items():
        folder = tmp_path_factory.mktemp(f"cache-{path}")
        out[path] = folder, _efforts(text, method, compiled=True, cache=folder)
    return out


@pytest.mark.parametrize("path, edit", CASES, ids=[f"{p}-{e}" for p, e in CASES])
def test_an_edited_scene_gets_its_own_numbers_from_the_cache(filled, path, edit, monkeypatch):
    text, method, edits = PATHS[path]
    old, new, count = edits[edit]
    assert text.count(old) == count
    edited = text.replace(old, new)
    folder, unedited = filled[path]
    compilations = []
    real_compile = compiled_module._compile
    monkeypatch.setattr(compiled_module, "_compile",
                        lambda *args: compilations.append(args) or real_compile(*args))
    cached = _efforts(edited, method, compiled=True, cache=folder)
    reference = _efforts(edited, method, compiled=False, cache=None)
    scale = np.abs(reference).max()
    assert np.abs(cached - reference).max() <= 1e-12 * scale
    assert np.abs(unedited - reference).max() > 1e-3 * scale  # the edit matters
    if path == "tree" and edit == "law coefficient":
        # a time law is an input of the tree Function: the cached library is reused, and fed
        # the edited law's values
        assert compilations == []
