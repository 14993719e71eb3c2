"""Ground that is not flat: a plane of any slope with steps (the scene's ``[ground]`` slope,
heading and steps). Scheduled feet stand on it, their friction cones about its normal; a robot
description walks up it. Checked against closed forms written here (not the terrain's code):
heights and normals of the plane and the steps, stance feet on footholds on the slope and on
each tread, the ground forces balancing the rate of change of momentum of the bodies' motions,
Pinocchio's efforts (live when installed), friction judged about the slope's normal, a swing
too low for a step's edge named with the foot and the time."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from robots import check_pinocchio, described_walk, foot_on_ground, momentum_gap

import hexapod as hx
from hexapod.errors import ModelError
from hexapod.scene import GroundForces
from legs.walker import StepPath

ROBOTS = Path(__file__).resolve().parents[1] / "data" / "robots"
SLOPE = np.radians(10.0)
FEET = ("LF", "RF", "LH", "RH")


def _quadruped(tmp_path, ground: str, *changes) -> Path:
    """The project's quadruped with ``ground`` lines added to its ``[ground]``."""
    for name in ("quadruped.urdf", "quadruped-motors.toml"):
        (tmp_path / name).write_text((ROBOTS / name).read_text())
    text = (ROBOTS / "quadruped.toml").read_text().replace("[ground]\n", f"[ground]\n{ground}\n")
    for old, new in changes:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "robot.toml"
    path.write_text(text)
    return path





def test_the_ground_has_the_height_and_normal_of_a_plane_with_steps():
    ground = GroundForces(slope=10.0, heading=30.0, steps=[[0.2, 0.03], [0.5, -0.01]])
    terrain = ground.terrain
    c, s = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
    x, y = np.array([0.0, 0.3, 0.5, 1.0]), np.array([0.1, -0.2, 0.4, 0.2])
    d = c * x + s * y
    expected = np.tan(SLOPE) * d + 0.03 * (d >= 0.2) - 0.01 * (d >= 0.5)
    assert np.abs(terrain.height(x, y) - expected).max() < 1e-15
    normal = terrain.normal()  # normal to the plane's two tangents, pointing up
    up_slope = np.array([c, s, np.tan(SLOPE)])
    across = np.array([-s, c, 0.0])
    assert abs(normal @ up_slope) < 1e-15 and abs(normal @ across) < 1e-15
    assert normal[2] > 0 and np.linalg.norm(normal) == pytest.approx(1.0, abs=1e-15)
    axes = terrain.axes()
    assert np.abs(axes @ axes.T - np.eye(3)).max() < 1e-15 and np.linalg.det(axes) > 0
    assert np.array_equal(axes[2], normal)
    assert np.array_equal(GroundForces().terrain.axes(), np.eye(3))


@pytest.mark.parametrize("key, value, message", [
    ("slope", 75.0, "less than 60 degrees"),
    ("steps", [[0.2]], "two finite numbers"),
    ("heading", float("nan"), "finite number of degrees"),
])
def test_a_bad_ground_shape_is_named(key, value, message):
    problems = GroundForces(**{key: value}, source="scene.toml, ground").problems()
    assert len(problems) == 1 and message in problems[0].message
    assert problems[0].where.startswith(f"scene.toml, ground.{key}")


def test_the_ground_shape_is_written_read_and_converted_with_the_length_unit(tmp_path):
    scene = hx.Scene("steps", length_unit="mm")
    scene.ground = GroundForces(slope=5.0, heading=90.0, steps=((300.0, 30.0), (600.0, -20.0)))
    path = hx.write_scene(scene, tmp_path / "steps.toml")
    again = hx.read_scene(path)
    assert again.ground.terrain == scene.ground.terrain
    assert again.in_si().ground.terrain.steps == ((0.3, 0.03), (0.6, -0.02))
    bad = tmp_path / "bad.toml"
    bad.write_text(path.read_text().replace("steps = [", "steps = [7, "))
    with pytest.raises(ModelError, match=r"ground\.steps.*list of 2 numbers, got 7"):
        hx.read_scene(bad)


def test_a_model_keeps_the_ground_shape_it_was_built_on(tmp_path):
    model = hx.assemble(hx.load_scene(_quadruped(tmp_path, "")))
    model.with_ground(GroundForces(policy="friction", mu=0.5), "")  # only the policy's numbers
    with pytest.raises(ValueError, match="ground's shape"):
        model.with_ground(GroundForces(policy="friction", slope=10.0), "")


@pytest.fixture(scope="module")
def slope():
    return described_walk("quadruped-slope")


def test_stance_feet_stand_on_the_slope_and_the_forces_balance_the_motion(slope):
    """data/robots/quadruped-slope.toml: its walk up 10 degrees, a stride."""
    scene, model, result, stored = slope
    for foot in FEET:
        contact = scene.joints[f"{foot}/ground"]
        position, foothold, stance = foot_on_ground(scene, model, result, contact)
        assert stance.sum() >= 19
        on_slope = np.column_stack([foothold[:, :2], np.tan(SLOPE) * foothold[:, 0]])
        assert np.abs(position[stance] - on_slope[stance]).max() < 1e-12
    assert momentum_gap(model, result) < 1e-9
    trunk = scene.drivers["trunk/z"].law  # rest height above the plane, up it at the speed
    assert trunk(1.2) - trunk(0.0) == pytest.approx(np.tan(SLOPE) * 0.1, abs=1e-15)
    check_pinocchio(model, result, stored)


def _statuses_about(normal, mu, force, stance, weight) -> np.ndarray:
    """The feet's statuses judged here, the slope's normal written out: ``pull`` below zero
    normal force, ``slip`` outside the exact cone, by 1e-7 of the weight (the statuses')."""
    pushed = force @ normal
    sliding = np.linalg.norm(force - pushed[..., None] * normal, axis=-1)
    tolerance = 1e-7 * weight
    out = np.where(stance, "ok", "swing").astype("<U5")
    out[stance & (sliding > mu * np.maximum(pushed, 0.0) + tolerance)] = "slip"
    out[stance & (pushed < -tolerance)] = "pull"
    return out


def test_friction_is_judged_about_the_slope_s_normal(slope, tmp_path):
    """Up a 10-degree slope the feet must push along it (the weight's component, tan 10 =
    0.18 of the normal force on average); the statuses are those of cones about the slope's
    normal. The trunk planned with the whole robot and the friction (``trunk = "whole-body"``)
    is carried at every sample by mu = 0.8 (the lumped plan alone fell short just before the
    fore feet touched down: 10 of 201 samples); at mu = 0.15 some foot slips at most
    samples."""
    scene, model, result, _ = slope
    normal = np.array([-np.sin(SLOPE), 0.0, np.cos(SLOPE)])
    weight = model.total_mass * 9.81
    stance = result.ground_status != "swing"
    assert np.array_equal(result.ground_status, _statuses_about(
        normal, 0.8, result.ground_force, stance, weight))
    assert result.feasible
    force = result.ground_force
    up = np.array([np.cos(SLOPE), 0.0, np.sin(SLOPE)])  # on average the feet hold the weight's
    held = (force @ up).sum(axis=1).mean() / (weight * np.sin(SLOPE))
    assert 0.8 < held < 1.2  # component along the slope (the stride's accelerations average out)
    slippery = _quadruped(tmp_path, "slope = 10", ("mu = 0.8", "mu = 0.15"))
    times = result.times[::4]
    steep = hx.inverse_dynamics(hx.assemble(hx.load_scene(slippery)), times)
    slipping = (steep.ground_status == "slip").any(axis=1)
    assert not steep.feasible and slipping.mean() >= 0.5  # the sway's pushes help at some
    assert np.array_equal(steep.ground_status, _statuses_about(
        normal, 0.15, steep.ground_force, steep.ground_status != "swing", weight))


def test_the_hexapod_climbs_two_steps_with_each_foot_on_its_tread():
    """data/robots/hexapod3-steps.toml: the three-joint hexapod's tripod up two 3 cm steps
    (x = 0.27 and 0.43 m), sampled every 0.1 s over 9 s. Every foot lands on the treads
    beyond each step as it crosses, the forces balance the motion, the friction policy
    carries it, the efforts are Pinocchio's, the trunk rises by both steps."""
    scene, model, result, stored = described_walk("hexapod3-steps")
    for foot in ("L1", "L2", "L3", "R1", "R2", "R3"):
        contact = scene.joints[f"{foot}/ground"]
        position, foothold, stance = foot_on_ground(scene, model, result, contact)
        tread = 0.03 * (foothold[:, 0] >= 0.27) + 0.03 * (foothold[:, 0] >= 0.43)
        on_tread = np.column_stack([foothold[:, :2], tread])
        assert np.abs(position[stance] - on_tread[stance]).max() < 1e-12, foot
        assert tread[0] < 0.06 and tread[-1] == 0.06, foot  # it climbed in the window
    assert momentum_gap(model, result) < 1e-9
    assert result.feasible
    trunk = scene.drivers["trunk/z"].law
    assert trunk(100.0) - trunk(-100.0) == pytest.approx(0.06, abs=1e-15)
    check_pinocchio(model, result, stored)


def test_a_foot_path_over_a_step_is_smooth_and_on_both_treads():
    """The rise is taken in the first half of the swing before the stance it starts (its
    derivatives against central differences with the other step paths':
    tests/test_robot_description.py), standing on each tread in stance."""
    path = StepPath(start=0.0, advance=0.0, lift=0.05, duty=0.75, period=1.0, lift_off=0.25,
                    rises_at=(2.0,), rises=(0.03,))
    # stance 1 ends at 1.25 s (lift-off), the swing to stance 2 lasts until 1.5 s
    assert np.ptp(path(np.linspace(0.5, 1.25, 9))) == 0.0 and path(1.0) == 0.0
    assert np.all(path(np.linspace(1.5, 2.25, 9)) == 0.03)
    # up within the swing's first half (1.25 to 1.375 s), over the riser's level after it
    up = path(np.array([1.375, 1.4, 1.45])) - 0.05 * 1024 * (
        (np.array([1.375, 1.4, 1.45]) - 1.25) / 0.25 * (1 - (np.array([1.375, 1.4, 1.45])
                                                              - 1.25) / 0.25)) ** 5
    assert np.abs(up - 0.03).max() < 1e-14


def test_a_swing_too_low_for_a_step_is_one_clear_message(tmp_path):
    """At x = 0.32 m the right fore foot's swing starts close to the riser: the foot has not
    risen 1 cm above the edge when it passes it, named with the foot and time; the command
    line says the same, exit 1, nothing written."""
    from commands import in_process

    path = _quadruped(tmp_path, "steps = [[0.32, 0.03]]")  # lift 4 cm
    with pytest.raises(ModelError, match=r"foot RF's swing at t = \S+ s passes the step at "
                                         r"0.32 m \S+ mm above its edge, less than the "
                                         r"clearance of 10 mm"):
        hx.load_scene(path)
    before = set(tmp_path.iterdir())
    done = in_process("report", str(path), "--no-figures", cwd=tmp_path)
    assert done.returncode == 1 and "foot RF's swing" in done.stderr
    assert "Traceback" not in done.stderr and set(tmp_path.iterdir()) == before


def test_a_study_varies_a_robot_description_s_ground_and_gait(tmp_path):
    """A study of a robot description sets its own keys (ground.slope, gait.step_height)
    before it walks and a scene key (the trunk's mass, a payload) on its scene after: each
    case equals the description written with those values and walked by hand."""
    from hexapod.sweeps import read_study, run_study

    _quadruped(tmp_path, "")
    study = tmp_path / "study.toml"
    study.write_text('[study]\nscene = "robot.toml"\n[fixed]\n"gait.step_height" = 0.05\n'
                     '"body.trunk.mass" = 9.0\n[vary."ground.slope"]\nvalues = [0.0, 10.0]\n'
                     '[job]\nsamples = 3\nduration = 0.2\nmetrics = ["peak_ground"]\n')
    rows = run_study(read_study(study)).rows
    for row in rows:
        assert row["status"] == "ok", row["message"]
        slope = row["params"]["ground.slope"]
        folder = tmp_path / f"{slope:g}"
        folder.mkdir()
        path = _quadruped(folder, f"slope = {slope}", ("step_height = 0.04",
                                                       "step_height = 0.05"))
        scene = hx.load_scene(path)
        scene.bodies["trunk"].mass = 9.0
        result = hx.inverse_dynamics(hx.assemble(scene), np.linspace(0.0, 0.2, 3))
        peak = np.linalg.norm(result.ground_force, axis=-1).max(axis=0)
        np.testing.assert_allclose([row["metrics"][f"peak_ground:{foot}"] for foot in FEET],
                                   peak, rtol=1e-9)
    assert rows[0]["metrics"]["peak_ground:LF"] != rows[1]["metrics"]["peak_ground:LF"]
