"""A robot no one wrote code for: a URDF and a robot description walk through the engine's own
kinematics (the trunk's pose and the feet's paths as guides), with no inverse kinematics of its
own. Checked on the project's small quadruped (data/robots/quadruped.toml) and its hexapod of
three joints a leg (data/robots/hexapod3.toml, a tripod): stance feet stay on their footholds,
the ground forces balance the rate of change of momentum computed from the bodies' motions
alone, the trunk follows its path, the efforts are Pinocchio's, the feet push inside their
friction cones; bad descriptions are one clear message."""

from __future__ import annotations

import copy
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np
import pytest

import hexapod as hx
from hexapod.errors import ModelError
from hexapod.spatial import rotation_from_euler_parameters
from legs.walker import PATTERNS, StepPath, roles

ROBOTS = Path(__file__).resolve().parents[1] / "data" / "robots"
QUADRUPED = ROBOTS / "quadruped.toml"
FIXTURES = Path(__file__).resolve().parent / "data"
#: The project's own robots, each with Pinocchio's torques for a stride of its gait
#: (tests/data/NAME_rnea.npz, by tests/data/make_walking_fixture.py --NAME; CI has no Pinocchio).
DESCRIBED = ("quadruped", "hexapod3")


@dataclass(frozen=True)
class Walk:
    """A robot of data/robots walking the stride of its fixture (the quadruped 24 samples of
    its walk, the hexapod 20 of its tripod; the stride's end left out): every foot lifts off
    and touches down."""

    stored: dict
    scene: hx.Scene
    model: hx.Model
    result: hx.InverseResult


@cache
def walking(name: str) -> Walk:
    """The walk of ``name`` (once per test process: the quadruped's feeds several tests)."""
    with np.load(FIXTURES / f"{name}_rnea.npz", allow_pickle=False) as data:
        stored = {key: data[key] for key in data.files}
    scene = hx.load_scene(ROBOTS / f"{name}.toml")
    model = hx.assemble(scene)
    return Walk(stored, scene, model, hx.inverse_dynamics(model, stored["times"]))


@pytest.fixture(scope="module", params=DESCRIBED)
def walk(request) -> Walk:
    return walking(request.param)


def foot_positions(scene, model, result, foot: str) -> np.ndarray:
    """The world position of ``foot``'s point at every sample (N, 3)."""
    contact = scene.joints[f"{foot}/ground"]
    body = scene.bodies[contact.child]
    point = contact.child_frame.position - np.asarray(body.com, dtype=float)
    info = model.bodies[model.body_index[body.name]]
    return np.array([q[info.q][:3] + np.asarray(rotation_from_euler_parameters(q[info.q][3:]))
                     @ point for q in result.q])


def test_stance_feet_stay_on_their_footholds(walk):
    scene, model, result = walk.scene, walk.model, walk.result
    for name in result.contacts:
        contact = scene.joints[name]
        position = foot_positions(scene, model, result, name.removesuffix("/ground"))
        stance = hx.scene.contacts.in_stance(contact, result.times)
        k = np.floor(result.times / contact.period - contact.lift_off) + 1.0
        foothold = contact.foothold + k[:, None] * contact.advance
        assert stance.sum() >= int(contact.duty * result.times.size) - 1  # the duty's share
        assert np.abs(position[stance] - foothold[stance]).max() < 1e-12


def test_ground_forces_balance_the_momentum_of_the_bodies_motions(walk):
    model, result = walk.model, walk.result
    weight = model.total_mass * 9.81
    momentum_rate = sum(b.mass * result.v_dot[:, b.v][:, :3] for b in model.bodies)
    gravity = model.total_mass * np.asarray(model.gravity)
    balance = result.ground_force.sum(axis=1) + gravity - momentum_rate
    assert np.abs(balance).max() < 1e-9 * weight


def test_the_trunk_follows_its_path_and_the_joints_carry_the_efforts(walk):
    """The trunk on its guides' laws (the quadruped's swaying as planned, the hexapod's level),
    a stride a period; every joint carries an effort (at least a fiftieth of the largest: the
    hexapod's coxae carry the least, 8 % of its middle femurs')."""
    scene, model, result = walk.scene, walk.model, walk.result
    trunk = model.bodies[model.body_index["trunk"]]  # its frame is its centre of mass
    for k, axis in enumerate("xy"):
        law = scene.drivers[f"trunk/{axis}"].law
        assert np.abs(result.q[:, trunk.q][:, k] - law(result.times)).max() < 1e-12
    contact = scene.joints[result.contacts[0]]
    x = scene.drivers["trunk/x"].law
    assert x(contact.period) - x(0.0) == pytest.approx(contact.advance[0])
    assert contact.advance[0] > 0.05  # the quadruped's 0.1 m, the hexapod's 0.08 m
    index = {name: k for k, name in enumerate(result.joints)}
    efforts = result.effort[:, [index[str(name)] for name in walk.stored["joints"]]]
    assert len(walk.stored["joints"]) == 3 * len(result.contacts)  # three joints a leg
    peaks = np.abs(efforts).max(axis=0)
    assert np.all(np.isfinite(efforts)) and np.all(peaks > 0.02 * peaks.max())


def test_the_friction_policy_carries_the_walk_at_every_sample(walk):
    """The friction policy finds forces at every sample, and they are what it says: each
    stance foot pushes (normal force at least 0) with its tangential force inside the friction
    cone of mu, to round-off (1e-9 of the weight: a foot just touching down carries ~1e-15 N)."""
    result, mu = walk.result, walk.scene.ground.mu
    assert result.policy == "friction" and result.feasible and not result.infeasible.any()
    force = result.ground_force
    stance = np.asarray(result.ground_status) != "swing"
    tol = 1e-9 * walk.model.total_mass * 9.81
    assert np.all(force[..., 2][stance] >= -tol)
    assert np.all(np.hypot(force[..., 0], force[..., 1])[stance]
                  <= mu * force[..., 2][stance] + tol)
    assert np.all(force[~stance] == 0.0)  # no force on a foot in the air


def test_a_level_trunk_is_not_carried_by_the_quadrupeds_feet(tmp_path):
    """With a level trunk the quadruped's centre of mass leaves the support polygon and feet
    would pull or slip (its planned trunk is carried: the test above)."""
    planned = walking("quadruped").result
    level = _description(tmp_path, QUADRUPED.read_text().replace('trunk = "planned"',
                                                                  'trunk = "level"'))
    result = hx.inverse_dynamics(hx.assemble(hx.load_scene(level)), planned.times)
    assert result.infeasible.sum() >= 3


def test_the_joint_efforts_are_pinocchios_with_the_ground_reactions_at_the_feet(walk):
    """Pinocchio's floating-base recursive Newton-Euler algorithm, on the same URDF robot's
    motion with the reported ground reactions applied at the feet, gives the joint efforts to
    1e-8 of the largest (2.3e-15 for the quadruped, 3.7e-15 for the hexapod when the fixtures
    were made); live when Pinocchio is installed (the next test), its free flyer then balanced
    to 1e-8 of the weight."""
    stored, result = walk.stored, walk.result
    index = {name: k for k, name in enumerate(result.joints)}
    efforts = result.effort[:, [index[str(name)] for name in stored["joints"]]]
    scale = np.abs(stored["pinocchio"]).max()
    assert str(stored["policy"]) == result.policy
    assert np.array_equal(stored["contacts"], result.contacts)
    assert np.abs(efforts - stored["pinocchio"]).max() < 1e-8 * scale
    assert np.abs(stored["base"]).max() < 1e-8 * scale


def test_the_joint_efforts_are_pinocchios_live(walk):
    pytest.importorskip("pinocchio")
    from script_loader import load_script

    model, result = walk.model, walk.result
    script = load_script("tests/data/make_walking_fixture.py")
    comparison = script.pinocchio_rnea(hx.simulation.motion_model(model, result), result)
    assert comparison.placement_gap < 1e-12 and comparison.motion_gap < 1e-10
    assert comparison.difference < 1e-8
    assert np.abs(comparison.base[:, :3]).max() < 1e-8 * model.total_mass * 9.81


def test_the_step_path_leaves_and_rejoins_the_ground_at_rest():
    """Zero velocity and acceleration at lift-off and touch-down, standing still in stance, one
    stride per period; the derivatives against central differences."""
    law = StepPath(start=0.1, advance=0.12, lift=0.0, duty=0.75, period=1.0, lift_off=0.25)
    lift = StepPath(start=0.0, advance=0.0, lift=0.04, duty=0.75, period=1.0, lift_off=0.25)
    climb = StepPath(start=0.0, advance=0.0, lift=0.05, duty=0.75, period=1.0, lift_off=0.25,
                     rises_at=(2.0,), rises=(0.03,))  # a step's rise on the swing to stance 2
    ends = np.array([0.25, 0.5, 1.25, 1.5])  # lift-offs and touch-downs
    for path in (law, lift, climb):
        _, rate, acceleration = path.evaluate(ends)
        assert np.abs(rate).max() < 1e-12 and np.abs(acceleration).max() < 1e-9
        t = np.linspace(0.0, 2.0, 97) + 0.0031
        h = 1e-5
        value, rate, acceleration = path.evaluate(t)
        assert np.abs((path(t + h) - path(t - h)) / (2 * h) - rate).max() < 1e-7
        assert np.abs((path.evaluate(t + h)[1] - path.evaluate(t - h)[1]) / (2 * h)
                      - acceleration).max() < 1e-7 * np.abs(acceleration).max()  # h^2 terms
    stance = np.linspace(0.5, 1.24, 20)
    assert np.ptp(law(stance)) == 0.0 and law(1.5) - law(0.5) == pytest.approx(0.12)
    assert lift(0.375) == pytest.approx(0.04)  # the top of the swing


def test_feet_take_their_roles_from_where_they_stand():
    rest = {"a": np.array([0.2, 0.1, 0]), "b": np.array([0.2, -0.1, 0]),
            "c": np.array([-0.2, 0.1, 0]), "d": np.array([-0.2, -0.1, 0])}
    assert roles(rest) == {"a": "LF", "c": "LH", "b": "RF", "d": "RH"}
    six = {f"f{k}": np.array([0.2 - 0.2 * (k % 3), 0.1 if k < 3 else -0.1, 0])
           for k in range(6)}
    assert sorted(roles(six).values()) == sorted(PATTERNS[6]["tripod"][0])
    with pytest.raises(ValueError, match="as many on each side"):
        roles({"a": np.array([0.2, 0.1, 0]), "b": np.array([0.2, 0.2, 0])})


def _description(tmp_path, text: str) -> Path:
    for name in ("quadruped.urdf", "quadruped-motors.toml"):
        (tmp_path / name).write_text((ROBOTS / name).read_text())
    path = tmp_path / "robot.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("change, message", [
    (('LF = { link = "LF_shank"', 'LF = { link = "LF_foot"'), "no link 'LF_foot'"),
    (('pattern = "walk"', 'phases = { LF = 0.25, RF = 0.75, LH = 0.0 }'), "forgets RH"),
    (('pattern = "walk"', 'pattern = "tripod"'), "must be one of walk, trot, pace, bound"),
    (('urdf = "quadruped.urdf"', 'urdf = "nowhere.urdf"'), "no file"),
    (('duty = 0.85', 'duty = 1.5'), "gait.duty"),
    (('actuators = "quadruped-motors.toml"', 'actuators = "motors.toml"'),
     "needs an actuator table file"),
    (('trunk = "planned"', 'trunk = "bouncing"'), "gait.trunk"),
    (('mu = 0.8', 'friction = 0.8'), "ground.friction"),
    (('"*_knee" = -1.2', '"*_kne" = -1.2'), "robot.rest.*_kne"),
    # the keys a robot's feet, gait and coupled joints gained with the cockroach
    (('point = [0.0, 0.0, -0.2] }', 'point = [0.0, 0.0, -0.2], offset = [0.1] }'),
     "robot.feet.LF"),
    (('trunk = "planned"', 'trunk = "planned"\nheight = -0.3'), "gait.height"),
    (('trunk = "trunk"', 'trunk = "trunk"\ncoupled = { "*_knee" = { bend = 8 } }'),
     "robot.coupled.*_knee"),
    (('trunk = "trunk"', 'trunk = "trunk"\ncoupled = { "*_knee" = { lift = "up" } }'),
     "{ lift = DEGREES }"),
])
def test_a_bad_description_is_one_clear_message(tmp_path, change, message):
    text = QUADRUPED.read_text()
    assert change[0] in text
    path = _description(tmp_path, text.replace(*change))
    with pytest.raises(ModelError) as caught:
        hx.load_scene(path)
    assert message in str(caught.value) and str(path) in str(caught.value)


@pytest.mark.parametrize("change, message", [
    (('LF = { link = "LF_shank"', 'LF = { link = "LF_foot"'), "no link 'LF_foot'"),
    # the knees bent backwards: out of the URDF's range from the start
    (('"*_flexion" = 0.6, "*_knee" = -1.2', '"*_flexion" = -0.6, "*_knee" = 1.2'),
     "): joint 'LF_knee' leaves its range [-2.6, 0] rad at t = 0 s ("),
    # a trot of duty 0.5: the diagonals would hand the trunk over in no time
    (('pattern = "walk"\nduty = 0.85 ', 'pattern = "trot"\nduty = 0.5 '),
     "the feet LF and RH hand the robot to LH and RF with no time with more feet down: give "
     "the gait a duty factor above 0.5"),
])
def test_the_command_line_refuses_a_bad_description_and_writes_nothing(tmp_path, change,
                                                                       message):
    from commands import in_process

    path = _description(tmp_path, QUADRUPED.read_text().replace(*change))
    before = set(tmp_path.iterdir())
    done = in_process("report", str(path), "--no-figures", "--samples", "25", cwd=tmp_path)
    error = done.stderr[done.stderr.index("hexapod: error:"):]  # one error, nothing after
    assert done.returncode == 1 and error.count("hexapod: error:") == 1 and message in error
    assert "Traceback" not in done.stderr and set(tmp_path.iterdir()) == before


def test_a_stride_too_long_names_the_foot_out_of_reach_and_how_far_and_writes_nothing(
        tmp_path):
    """A stride of 0.6 m puts the left hind foot's path 0.440 m from its hip at t = 0 (both
    from the guides' laws: the hip is the trunk's origin plus (-0.18, 0.1, 0) m): its leg of
    0.4 m, straight and pointing at it, leaves it 40.3 mm off, along the hip-to-path line.
    `hexapod report` says so in one message naming the foot and the time, and writes
    nothing."""
    from commands import in_process

    path = _description(tmp_path, QUADRUPED.read_text().replace("stride = 0.1", "stride = 0.6"))
    scene = hx.load_scene(path)
    guides = {name: float(np.ravel(scene.drivers[name].law(0.0))[0])
              for name in ("trunk/x", "trunk/y", "trunk/z", "LH/x", "LH/y", "LH/z")}
    hip = np.array([guides[f"trunk/{a}"] for a in "xyz"]) + [-0.18, 0.1, 0.0]
    target = np.array([guides[f"LH/{a}"] for a in "xyz"])
    far = np.linalg.norm(target - hip)
    miss = -(far - 0.4) * (target - hip) / far * 1e3  # reached - asked, mm
    before = set(tmp_path.iterdir())
    done = in_process("report", str(path), "--no-figures", cwd=tmp_path)
    assert done.returncode == 1 and "Traceback" not in done.stderr
    assert done.stderr.strip().splitlines()[-1] == (
        f"hexapod: error: model 'quadruped' ({path}): at t = 0 s the guides ask for a pose out "
        f"of the joints' reach; as near as they come, guide 'LH' is {(far - 0.4) * 1e3:.3g} mm "
        f"off (LH/x {miss[0]:+.3g} mm, LH/y {miss[1]:+.3g} mm, LH/z {miss[2]:+.3g} mm) (check "
        "the gait: a stride or a step too long for the legs, or the rest posture)")
    assert set(tmp_path.iterdir()) == before


def test_a_knee_leaves_its_range_at_the_first_sample_its_angle_passes_it():
    """The walk's left fore knee, its angle measured from the thigh's and the shank's poses
    (the rotation between their joint frames about the axis), passes -1.15 rad first at a
    sample inside the stride: a URDF range of [-2.6, -1.15] rad names it there, with the
    angle."""
    from hexapod.algorithms.joint_limits import check_joint_limits
    from hexapod.errors import JointLimitError

    walk = walking("quadruped")
    model, result = walk.model, walk.result
    _, rotation = hx.body_poses(model, result.q)
    joint = next(j for j in model.joints if j.name == "LF_knee")
    R = (np.swapaxes(rotation[:, joint.parent] @ joint.parent_frame.rotation, 1, 2)
         @ rotation[:, joint.child] @ joint.child_frame.rotation)
    sine = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0],
                     R[:, 1, 0] - R[:, 0, 1]], axis=1) @ joint.axis / 2
    angle = np.arctan2(sine, (np.trace(R, axis1=1, axis2=2) - 1) / 2)
    k = int(np.argmax(angle > -1.15))
    assert 0 < k and np.all(angle < 0)  # inside the stride, bent forwards throughout
    # the walk's own scene, copied (its knee's limits are changed here): loading
    # data/robots/quadruped.toml again plans its trunk again, 1.8 s for the same scene
    tight = copy.deepcopy(walk.scene)
    tight.joints["LF_knee"].limits = np.array([-2.6, -1.15])
    with pytest.raises(JointLimitError) as caught:
        check_joint_limits(hx.assemble(tight), result.times, result.q)
    error = caught.value
    assert (error.joint, error.time) == ("LF_knee", result.times[k])
    assert error.value == pytest.approx(angle[k], abs=1e-12)


@pytest.mark.parametrize("slope", [0.0, 10.0])
@pytest.mark.parametrize("gait", ["solo12", "solo12-trot"])
def test_solo12_walks_with_its_feet_on_their_footholds_and_pinocchios_efforts(tmp_path, gait,
                                                                              slope):
    """Solo12 from the installed example-robot-data (the robots extra; large, so not in the
    default install), walking and trotting, on flat ground and up 10 degrees: a stride keeps
    the stance feet on their footholds (on the slope: ``z = tan(10) x``; 1e-12 m), its ground
    forces balance the bodies' momentum rate (1e-9 of the weight), the friction policy finds
    them inside the cones at every sample and, with Pinocchio installed, its efforts are
    Pinocchio's RNEA with the ground reactions at the feet (1e-8 of the largest)."""
    from importlib.metadata import PackageNotFoundError, distribution

    try:
        distribution("example-robot-data")
    except PackageNotFoundError:
        pytest.skip("example-robot-data is not installed (pip install 'hexapod[robots]')")
    path = tmp_path / f"{gait}.toml"
    path.write_text((ROBOTS / f"{gait}.toml").read_text().replace(
        "[ground]\n", f"[ground]\nslope = {slope}\n"))
    scene = hx.load_scene(path)
    model = hx.assemble(scene)
    period = scene.joints["FL/ground"].period
    result = hx.inverse_dynamics(model, np.linspace(0.0, period, 24, endpoint=False))
    assert result.feasible
    for foot in ("FL", "FR", "HL", "HR"):
        contact = scene.joints[f"{foot}/ground"]
        stance = hx.scene.contacts.in_stance(contact, result.times)
        k = np.floor(result.times / contact.period - contact.lift_off) + 1.0
        foothold = contact.foothold + k[:, None] * contact.advance
        foothold[:, 2] += np.tan(np.radians(slope)) * foothold[:, 0]
        position = foot_positions(scene, model, result, foot)
        assert np.abs(position[stance] - foothold[stance]).max() < 1e-12
    momentum_rate = sum(b.mass * result.v_dot[:, b.v][:, :3] for b in model.bodies)
    balance = (result.ground_force.sum(axis=1) + model.total_mass * np.asarray(model.gravity)
               - momentum_rate)
    assert np.abs(balance).max() < 1e-9 * model.total_mass * 9.81
    pytest.importorskip("pinocchio")
    from script_loader import load_script

    script = load_script("tests/data/make_walking_fixture.py")
    comparison = script.pinocchio_rnea(hx.simulation.motion_model(model, result), result)
    assert comparison.difference < 1e-8


def test_a_tripod_of_duty_one_half_plans_its_trunk(tmp_path):
    """At duty 0.5 the load passes from one tripod to the other with no foot fully loaded: the
    trunk's plan holds to the feet where there are some (it once raised an IndexError)."""
    for name in ("hexapod3.urdf", "hexapod3.toml"):
        (tmp_path / name).write_text((ROBOTS / name).read_text())
    path = tmp_path / "hexapod3.toml"
    path.write_text(path.read_text().replace("duty = 0.6", "duty = 0.5").replace(
        'trunk = "level"', 'trunk = "planned"'))
    scene = hx.load_scene(path)
    x = scene.drivers["trunk/x"].law
    assert x(1.0) - x(0.0) == pytest.approx(0.08)  # a stride a period, swaying about it
    assert np.all(np.isfinite(x(np.linspace(0.0, 1.0, 101))))


def test_the_report_checks_the_motors_the_description_names(tmp_path):
    """The quadruped's description names its motors (quadruped-motors.toml): its report
    checks every joint against them, as --actuators does, without being told."""
    from commands import in_process

    done = in_process("report", str(QUADRUPED), "--samples", "13", "--no-figures", "--out",
                      str(tmp_path / "out"), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    header = (tmp_path / "out" / "motors.csv").read_text().splitlines()[0].split(",")
    joints = {column.split(":", 1)[1] for column in header[1:]}
    assert len(joints) == 12 and {"use:LF_knee", "I:RH_abduction"} <= set(header)
    assert "24 V motor, 10:1" in (tmp_path / "out" / "summary.md").read_text()


def test_a_foot_about_to_lift_off_is_not_called_slipping_for_the_solver_s_tolerance():
    """2.4 ms before the left hind foot lifts off it carries 6e-5 N: the friction QP's own
    tolerance (DAQP's, 1e-6 of the weight by default) once left it 7e-5 N outside its cone,
    and the report said the quadruped slips there. The QP now holds its constraints to 1e-10
    of the weight, below the statuses' 1e-7."""
    model = walking("quadruped").model
    result = hx.inverse_dynamics(model, [0.5976, 1.1976])
    assert result.feasible, result.ground_status
