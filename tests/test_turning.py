"""A robot turning at a constant yaw rate (legs/turning.py) and a tilted trunk: the project's
quadruped turning left at 10 degrees a second (data/robots/quadruped-turn.toml), checked as
every described walk is (feet on their footholds, now on circles written out here with complex
numbers; the momentum balance; Pinocchio's efforts) and for the turn itself: the trunk's yaw,
its pose a stride later turned about the centre, the feet's paths smooth at touch-down."""

from __future__ import annotations

import numpy as np
import pytest
from robots import (
    ROBOTS,
    check_pinocchio,
    described_walk,
    foot_on_ground,
    momentum_gap,
    rest_feet,
)

import hexapod as hx
from hexapod.errors import ModelError
from hexapod.spatial import rotation_from_euler_parameters
from legs.turning import TurnPath

RATE = np.radians(10.0)  # rad/s
PERIOD, STRIDE = 1.2, 0.1
RADIUS = STRIDE / PERIOD / RATE  # the trunk's circle, 0.477 m


@pytest.fixture(scope="module")
def turn():
    return described_walk("quadruped-turn")


def _turned(points: np.ndarray, centre: complex, angle) -> np.ndarray:
    """``points`` (..., 2) turned by ``angle`` about ``centre``, as complex numbers."""
    z = (points[..., 0] + 1j * points[..., 1] - centre) * np.exp(1j * angle) + centre
    return np.stack([z.real, z.imag], axis=-1)


def test_stance_feet_stand_on_footholds_round_the_turn_and_forces_balance(turn):
    """Each foot's stance c stands where its rest position is when the trunk is at the middle
    of that stance: the rest turned about the circle's centre, 0.477 m left of the trunk's
    start, by 10 degrees a second times that time; footholds to 1e-12 m, on z = 0."""
    scene, model, result, stored = turn
    centre = _centre(scene)
    for name in ("LF", "RF", "LH", "RH"):
        contact = scene.joints[f"{name}/ground"]
        position, _, stance = foot_on_ground(scene, model, result, contact)
        k = np.floor(result.times / PERIOD - contact.lift_off) + 1.0
        middle = (contact.lift_off + k - contact.duty / 2) * PERIOD  # stance k's middle
        assert stance.sum() >= 19
        standing = _turned(_rest_foot(scene, name)[None, :2], centre, RATE * middle)
        assert np.abs(position[stance, :2] - standing[stance]).max() < 1e-12
        assert np.abs(position[stance, 2]).max() < 1e-12
    assert momentum_gap(model, result) < 1e-9
    assert result.feasible  # the friction policy carries the turn at every sample
    check_pinocchio(model, result, stored)


def _centre(scene) -> complex:
    """The turn's centre: ``RADIUS`` left of the trunk's frame at rest (over the origin, its
    sway not added), heading along ``x``."""
    return complex(0.0, RADIUS)


def _rest_foot(scene, name: str) -> np.ndarray:
    """Foot ``name``'s point in the world with the robot in its rest posture at t = 0."""
    return rest_feet("quadruped-turn")[name]


def test_the_trunk_turns_at_the_yaw_rate_and_repeats_a_stride_later_turned(turn):
    """The trunk's yaw (measured from its Euler parameters) is 10 degrees a second; its
    guides a stride later are the same pose turned by 12 degrees about the centre (the sway
    rides along the trunk's axes): it is the straight walk's sway, turned with the trunk."""
    scene, model, result, _ = turn
    trunk = model.bodies[model.body_index["trunk"]]
    yaw = [np.arctan2(R[1, 0], R[0, 0]) for R in
           (rotation_from_euler_parameters(q[trunk.q][3:]) for q in result.q)]
    assert np.abs(np.unwrap(yaw) - RATE * result.times).max() < 1e-12
    x, y = (scene.drivers[f"trunk/{axis}"].law for axis in "xy")
    t = np.linspace(0.0, PERIOD, 97)
    centre = _centre(scene)
    now = np.column_stack([x(t), y(t)])
    later = np.column_stack([x(t + PERIOD), y(t + PERIOD)])
    assert np.abs(later - _turned(now, centre, RATE * PERIOD)).max() < 1e-12
    # the sway along the trunk's axes is the straight walk's (planned the same way)
    straight = hx.load_scene(ROBOTS / "quadruped.toml")
    origin = np.zeros(3)  # the trunk's frame at rest, over the origin
    sway = (straight.drivers["trunk/x"].law(t) - origin[0] - STRIDE / PERIOD * t
            + 1j * (straight.drivers["trunk/y"].law(t) - origin[1]))
    assert np.abs(sway).max() > 0.02  # it sways by centimetres
    turned_sway = (now[:, 0] + 1j * now[:, 1] - centre) * np.exp(-1j * RATE * t) + 1j * RADIUS
    assert np.abs(turned_sway - sway).max() < 1e-12


def test_a_foot_leaves_and_rejoins_the_ground_at_rest_along_its_circle():
    """A turning foot's path: on its foothold in stance (zero rates), moving along the circle
    in swing with the rates of its own finite differences, at rest at lift-off and
    touch-down, and stance c + 1 a turn further round than stance c."""
    law = dict(centre_x=0.1, centre_y=0.5, radius=0.6, angle=-1.2, turn=0.2, duty=0.75,
               period=1.2, lift_off=0.25)
    x, y = TurnPath(axis=0, **law), TurnPath(axis=1, **law)
    lift_off, touch_down = 0.25 * 1.2, (0.25 + 0.25) * 1.2
    for path in (x, y):
        for t in (lift_off, touch_down):
            _, rate, acceleration = path.evaluate(np.array([t - 1e-9, t + 1e-9]))
            assert np.abs(rate).max() < 1e-12 and np.abs(acceleration).max() < 1e-6
        t = np.linspace(lift_off, touch_down, 2001)[1:-1]
        value, rate, acceleration = path.evaluate(t)
        h = 1e-6
        assert np.allclose(rate, (path(t + h) - path(t - h)) / (2 * h), rtol=0, atol=1e-7)
        rate_h = (path.evaluate(t + h)[1] - path.evaluate(t - h)[1]) / (2 * h)
        assert np.allclose(acceleration, rate_h, rtol=0, atol=1e-5)
    before = complex(x(lift_off - 0.1), y(lift_off - 0.1)) - complex(0.1, 0.5)
    after = complex(x(touch_down + 0.1), y(touch_down + 0.1)) - complex(0.1, 0.5)
    assert abs(before) == pytest.approx(0.6, abs=1e-15)
    assert np.angle(after / before) == pytest.approx(0.2, abs=1e-14)


def _description(tmp_path, gait: str, ground: str = "") -> str:
    for name in ("quadruped.urdf", "quadruped-motors.toml"):
        (tmp_path / name).write_text((ROBOTS / name).read_text())
    text = (ROBOTS / "quadruped.toml").read_text()
    text = text.replace("[gait]\n", f"[gait]\n{gait}\n")
    text = text.replace("[ground]\n", f"[ground]\n{ground}\n")
    path = tmp_path / "robot.toml"
    path.write_text(text)
    return path


def test_a_tilted_trunk_holds_its_pitch_and_roll_with_the_feet_on_their_footholds(tmp_path):
    """gait.pitch and gait.roll tilt the trunk (R = Rz(yaw) Ry(pitch) Rx(roll), measured from
    its Euler parameters); the feet stand where they do under a level trunk."""
    scene = hx.load_scene(_description(tmp_path, "pitch = -4\nroll = 3"))
    model = hx.assemble(scene)
    times = np.linspace(0.0, 1.2, 7)
    result = hx.inverse_dynamics(model, times)
    trunk = model.bodies[model.body_index["trunk"]]
    pitch, roll = np.radians(-4.0), np.radians(3.0)
    expected = (np.array([[np.cos(pitch), 0, np.sin(pitch)], [0, 1, 0],
                          [-np.sin(pitch), 0, np.cos(pitch)]])
                @ np.array([[1, 0, 0], [0, np.cos(roll), -np.sin(roll)],
                            [0, np.sin(roll), np.cos(roll)]]))
    for q in result.q:
        assert np.abs(rotation_from_euler_parameters(q[trunk.q][3:]) - expected).max() < 1e-12
    for name in ("LF", "RF", "LH", "RH"):
        position, foothold, stance = foot_on_ground(scene, model, result,
                                                    scene.joints[f"{name}/ground"])
        assert np.abs(position[stance] - foothold[stance]).max() < 1e-12
    assert momentum_gap(model, result) < 1e-9


@pytest.mark.parametrize("gait, ground, message", [
    ("yaw_rate = 10", "slope = 5", r"gait\.yaw_rate.*flat ground only"),
    ("pitch = 50", "", r"gait\.pitch.*must be in \(-45.0, 45.0\), got 50"),
    ("yaw_rate = 'left'", "", r"gait\.yaw_rate.*must be a number"),
])
def test_a_bad_turn_or_tilt_is_one_clear_message(tmp_path, gait, ground, message):
    with pytest.raises(ModelError, match=message):
        hx.load_scene(_description(tmp_path, gait, ground))


def test_a_turning_contact_is_written_and_read_back(tmp_path):
    """The contacts' ``turn`` and ``centre`` (a scene written out: the engine's keys) come
    back equal, and the footholds they give are the same."""
    scene = hx.load_scene(ROBOTS / "quadruped-turn.toml")
    path = hx.write_scene(scene, tmp_path / "turn.toml")
    again = hx.read_scene(path)
    for name in ("LF/ground", "RH/ground"):
        a, b = scene.joints[name], again.joints[name]
        assert a.turn == b.turn == pytest.approx(12.0, abs=1e-12)
        assert np.array_equal(a.centre, b.centre) and np.array_equal(a.foothold, b.foothold)
        t = np.linspace(0.0, 3.6, 37)
        for axis in range(3):
            footholds = [hx.scene.contacts.Foothold(c, axis)(t) for c in (a, b)]
            assert np.array_equal(*footholds)
