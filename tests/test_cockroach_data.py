"""The cockroach rebuilt: its legs placed by the engine's kinematics instead of its own inverse
kinematics, the walking robot built from its robot description by the general path, and the
figures of before kept to 1e-9.

``tests/data/cockroach_reference.npz`` holds the figures the cockroach's own inverse kinematics
gave (``tests/data/make_cockroach_reference.py``, written before it was deleted): every joint's
force and moment, every effort and the ground forces over one stride of each built-in scene of
the cockroach and of two design variants. The same numbers, to 1e-9 of the largest of each
quantity, say the motion is the same (the feet on the same paths, the joints the same angles,
rates and accelerations) and so is everything computed from it.
"""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import numpy as np
import pytest
from script_loader import load_script

REFERENCE = Path(__file__).resolve().parent / "data" / "cockroach_reference.npz"
TOLERANCE = 1e-9


def _fixture_script():
    """The fixture's maker as a module, without its folder on ``sys.path`` (tests/data holds a
    folder named ``pinocchio``, which would pass for the package where it is not installed)."""
    spec = importlib.util.spec_from_file_location(
        "make_cockroach_reference", REFERENCE.parent / "make_cockroach_reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


SCRIPT = _fixture_script()


@pytest.mark.parametrize("name", ["front-leg", "middle-leg", "hind-leg", "hexapod",
                                  "hexapod-held", "hexapod-standing", "hexapod-tetrapod",
                                  "hexapod-femur-1.1"])
def test_the_cockroach_keeps_its_figures(name):
    reference = np.load(REFERENCE)
    assert np.array_equal(reference["times"], SCRIPT.TIMES)
    now = SCRIPT.figures(SCRIPT.cases()[name]())
    # the same joints and contacts, by name (the general path lists a robot's contacts after
    # its joints, the built-in robot listed each leg's contact after the leg's joints)
    order = {}
    for names in ("joints", "contacts"):
        if f"{name}:{names}" in reference:
            before, after = list(reference[f"{name}:{names}"]), list(now[names])
            assert sorted(before) == sorted(after), names
            order[names] = [after.index(n) for n in before]
    for key, value in now.items():
        if value.dtype.kind in "US":
            continue
        value = value[:, order["contacts" if key == "ground_force" else "joints"]]
        before = reference[f"{name}:{key}"]
        scale = np.nanmax(np.abs(before))
        assert np.nanmax(np.abs(value - before)) <= TOLERANCE * scale, (name, key)


ROBOT = REFERENCE.parents[2] / "data" / "robots" / "cockroach.toml"


_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _same_text_to_round_off(written: str, now: str) -> None:
    """The same text with the same numbers to 1e-12 m (the bodies' places come from rotations
    whose last bit depends on the processor's vector unit: -1.4e-17 on one machine is 0.0 on
    another)."""
    assert _NUMBER.split(written) == _NUMBER.split(now)
    a = np.array([float(x) for x in _NUMBER.findall(written)])
    b = np.array([float(x) for x in _NUMBER.findall(now)])
    assert a.shape == b.shape
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


def test_the_cockroachs_description_is_what_its_script_writes():
    script = load_script("scripts/make_cockroach_robot.py")
    _same_text_to_round_off(ROBOT.read_text(), script.description_text())
    _same_text_to_round_off(ROBOT.with_suffix(".urdf").read_text(), script.urdf_text())


def test_the_cockroach_from_its_description_file_keeps_the_built_in_figures():
    """``data/robots/cockroach.toml`` beside its URDF, read as any robot's description: the
    built-in walking robot's figures of before (its bodies through the URDF's round trip)."""
    import hexapod as hx

    reference = np.load(REFERENCE)
    now = SCRIPT.figures(hx.load_scene(str(ROBOT)))
    for key in ("effort", "force", "torque", "ground_force"):
        names = "contacts" if key == "ground_force" else "joints"
        after = list(now[names])
        before = reference[f"hexapod:{key}"]
        value = now[key][:, [after.index(n) for n in reference[f"hexapod:{names}"]]]
        assert np.nanmax(np.abs(value - before)) <= TOLERANCE * np.nanmax(np.abs(before)), key
