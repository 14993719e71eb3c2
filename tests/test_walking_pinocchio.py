"""The walking robot against a second library: its joint efforts equal those of Pinocchio's
floating-base recursive Newton-Euler algorithm with the reported ground reactions applied at the
feet, to 1e-8 of the largest effort.

``tests/data/walking_rnea.npz`` holds Pinocchio's torques for one stride of the tripod gait
(``tests/data/make_walking_fixture.py``; CI has no Pinocchio): the efforts recomputed here must
match them. With Pinocchio installed the comparison is also redone live, and the free flyer's
generalized force must vanish (the ground reactions balance the robot).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from robots import builtin_model
from script_loader import load_script

import hexapod as hx

FIXTURE = Path(__file__).resolve().parent / "data" / "walking_rnea.npz"
TOLERANCE = 1e-8  # of the largest torque


@pytest.fixture(scope="module")
def stored():
    with np.load(FIXTURE, allow_pickle=False) as data:
        return {key: data[key] for key in data.files}


@pytest.fixture(scope="module")
def walking(stored):
    model = builtin_model("hexapod")  # the robot with a free trunk
    return model, hx.inverse_dynamics(model, stored["times"])


def _efforts(result, joints):
    index = {name: k for k, name in enumerate(result.joints)}
    return result.effort[:, [index[str(name)] for name in joints]]


def test_efforts_match_the_stored_pinocchio_torques(stored, walking):
    _, result = walking
    assert str(stored["policy"]) == result.policy
    efforts = _efforts(result, stored["joints"])
    scale = np.abs(stored["pinocchio"]).max()
    difference = np.abs(efforts - stored["pinocchio"]).max() / scale
    ground = np.abs(result.ground_force - stored["ground_force"]).max() \
        / np.abs(stored["ground_force"]).max()
    assert difference < TOLERANCE, (
        f"efforts differ from Pinocchio's by {difference:.2e} of the largest; the ground "
        f"forces differ from the stored ones by {ground:.2e} of the largest")
    # the fixture itself: Pinocchio agreed with the engine and the base was balanced
    assert np.abs(stored["hexapod"] - stored["pinocchio"]).max() / scale < TOLERANCE
    assert np.abs(stored["base"]).max() < TOLERANCE * scale


def test_efforts_match_pinocchio_live(walking):
    pytest.importorskip("pinocchio")
    script = load_script("tests/data/make_walking_fixture.py")
    model, result = walking
    comparison = script.pinocchio_rnea(model, result)
    assert comparison.angle_gap < 1e-12  # the driver laws are the angles of q
    assert comparison.placement_gap < 1e-12  # the same mechanism in both libraries
    assert comparison.motion_gap < 1e-10
    assert np.array_equal(comparison.hexapod, _efforts(result, comparison.joints))
    assert comparison.difference < TOLERANCE
    weight = sum(b.mass for b in model.bodies) * np.linalg.norm(model.gravity)
    size = model.characteristic_length
    assert np.abs(comparison.base[:, :3]).max() < TOLERANCE * weight
    assert np.abs(comparison.base[:, 3:]).max() < TOLERANCE * weight * size
