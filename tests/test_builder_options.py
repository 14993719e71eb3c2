"""The design options of the built-in scene builders (the entry points of ``hexapod.scenes``):
keyword-only, checked, and with no arguments the built-in scenes themselves.

Independent checks: the committed scene files; the robot's mass from the segments' table; the
centroidal balance (the feet's ground reactions plus gravity against the bodies' own
accelerations) and, for a payload, the exact change it makes to the ground reactions of a
motion the payload does not change (the walking robot's motion is prescribed); the stance feet
against their footholds (no slip); scene files read back.
"""

from __future__ import annotations

import inspect
import math
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from robots import builtin_model

import hexapod as hx
from legs.cockroach import SEGMENTS, STANCE_LENGTH_MM
from legs.front_leg import front_leg_walking, hind_leg_walking, middle_leg_walking
from legs.gait import GAITS
from legs.leg import SEGMENT_NAMES, leg_geometry
from legs.robot import (
    WALKING_DUTY,
    hexapod_held,
    hexapod_scene,
    hexapod_standing,
    hexapod_walking,
    robot_mass,
    walking_pattern,
)
from legs.stepping import FootPath, leg_spec, parse_leg

ROOT = Path(__file__).resolve().parent.parent
PERIOD = 0.5
TIMES = np.array([0.0, 0.11, 0.23, 0.37])  # a few instants of the stride (45 ms each)
PAYLOAD = 2.0  # kg, a tenth of the robot
#: Length factors the walking robot still reaches its paths with (coxa, femur, tibia, tarsus).
FACTORS = {"coxa_length": 1.1, "femur_length": 1.2, "tibia_length": 0.9, "tarsus_length": 0.8}
BUILDERS = {"hexapod": hexapod_walking, "hexapod-held": hexapod_held,
            "hexapod-standing": hexapod_standing, "front-leg": front_leg_walking,
            "middle-leg": middle_leg_walking, "hind-leg": hind_leg_walking}


def same_numbers(a: str, b: str, rel: float = 1e-13, floor: float = 1e-15) -> bool:
    """Two scene texts alike but for round-off in their numbers: relative ``rel``, and
    ``floor`` absolute for the numbers that are zero but for round-off (their lengths and angles
    are of order 0.1 to 1 m and rad)."""
    number = r"[-+]?(?:\d+\.?\d*(?:[eE][-+]?\d+)?|inf|nan)"
    if re.split(number, a) != re.split(number, b):
        return False
    x = np.array([float(s) for s in re.findall(number, a)])
    y = np.array([float(s) for s in re.findall(number, b)])
    return x.shape == y.shape and bool(np.all(np.abs(x - y) <= rel * np.abs(y) + floor))


def body_motion_balance(model, result):
    """Per sample: the sum of the bodies' ``m (a - g)`` (N, 3), the ground reactions' sum and
    the trunk's acceleration (world)."""
    inertial = np.zeros((result.times.size, 3))
    for b in model.bodies:
        inertial += b.mass * (result.v_dot[:, b.v][:, :3] - model.gravity)
    trunk = model.bodies[model.body_index["trunk"]]
    return inertial, result.ground_force.sum(axis=1), result.v_dot[:, trunk.v][:, :3]


def stance_slip(model, result) -> float:
    """The largest distance of a stance foot from its foothold (m), as
    ``scripts/studies/walking_checks.py`` measures it."""
    feet = hx.marker_trajectories(model, result.q, "foot")
    w = model.law_values(result.times)[0]
    worst = 0.0
    for contact in model.contacts:
        holds = [k for k, law in enumerate(model.laws)
                 if law.kind == "foothold" and law.contact is contact.schedule]
        stance = np.asarray(contact.in_stance(result.times))
        assert stance.any(), f"{contact.name}: no sample in stance"
        foot = feet[contact.name.split("/")[0] + "/tarsus"]
        worst = max(worst, float(np.abs(foot - w[holds].T)[stance].max()))
    return worst


@pytest.fixture(scope="module")
def walks():
    """The walking robot as built in, with a payload, and with other segment lengths: the
    model and its inverse dynamics at ``TIMES``."""
    out = {}
    for key, options in (("default", {}), ("payload", {"payload": PAYLOAD}),
                         ("lengths", FACTORS)):
        # the built-in robot is hexapod_walking() (test_no_arguments_give_the_committed_...)
        model = hx.assemble(hexapod_walking(**options)) if options else builtin_model("hexapod")
        out[key] = model, hx.inverse_dynamics(model, TIMES)
    return out


# ------------------------------------------------------------------ signatures and defaults


@pytest.mark.parametrize("name", sorted(BUILDERS))
def test_every_option_has_a_default_is_documented_and_is_keyword_only(name):
    entry = hx.builtin_scenes()[name]
    builder = entry.load()
    assert builder is BUILDERS[name]
    parameters = inspect.signature(builder).parameters.values()
    doc = inspect.getdoc(builder)
    documented = doc.split("Parameters\n----------\n")[1].split("\n\n")[0]
    legacy = {"feet", "scale", "name"} if name == "hexapod-standing" else set()
    for p in parameters:
        assert p.default is not inspect.Parameter.empty, p.name
        assert p.kind is inspect.Parameter.KEYWORD_ONLY or p.name in legacy, p.name
        assert re.search(rf"^{p.name}\b|, {p.name}\b", documented, flags=re.M), p.name
    assert "gait" in {p.name for p in parameters} or name == "hexapod-standing"


@pytest.mark.parametrize("name", ["front-leg", "middle-leg", "hind-leg", "hexapod"])
def test_no_arguments_give_the_committed_scene_files(name):
    committed = (ROOT / "data" / "scenes" / f"{name.replace('-', '_')}.toml").read_text()
    header = f"Built-in scene '{name}', written by 'hexapod scenes {name} --write'."
    # alike to round-off: the builders' trigonometry goes through NumPy and SciPy, whose last
    # bits differ between releases
    assert same_numbers(hx.scene.scene_text(BUILDERS[name](), header=header), committed)


def test_explicit_default_values_give_the_built_in_scenes():
    lengths = dict.fromkeys(FACTORS, 1.0)
    assert hx.scene.scene_text(hexapod_walking(gait="tripod", period=0.5, duty=0.6, scale=20,
                                               payload=0, **lengths)) \
        == hx.scene.scene_text(hexapod_walking())
    assert hx.scene.scene_text(hexapod_held(gait="tripod", period=0.5, duty=0.5, scale=20.0,
                                            payload=0.0, **lengths)) \
        == hx.scene.scene_text(hexapod_held())
    assert hx.scene.scene_text(hexapod_standing(feet=6, scale=20.0, payload=0.0, **lengths)) \
        == hx.scene.scene_text(hexapod_standing())
    assert hx.scene.scene_text(front_leg_walking(gait="tripod", period=0.5, scale=20.0)) \
        == hx.scene.scene_text(front_leg_walking())
    assert "_length" not in hx.scene.scene_text(hexapod_walking())  # no key more in the files


# ------------------------------------------------------------------ period and speed


def test_speed_and_period_give_the_same_scene():
    tripod = walking_pattern("tripod", None)
    speed = tripod.walking_speed(0.4, 20.0)  # the default duty 0.6
    assert speed == pytest.approx(STANCE_LENGTH_MM * 1e-3 * 20 / (0.6 * 0.4), rel=1e-15)
    assert same_numbers(hx.scene.scene_text(hexapod_walking(speed=speed)),
                        hx.scene.scene_text(hexapod_walking(period=0.4)))
    # the speed depends on the duty factor: at 0.75 the same speed is a shorter period
    slow = walking_pattern("tripod", 0.75).walking_speed(0.3, 20.0)
    assert same_numbers(hx.scene.scene_text(hexapod_walking(duty=0.75, speed=slow)),
                        hx.scene.scene_text(hexapod_walking(duty=0.75, period=0.3)))
    held = GAITS["wave"].walking_speed(0.6, 10.0)  # the held robot: the gait's own duty
    assert same_numbers(hx.scene.scene_text(hexapod_held(gait="wave", scale=10, speed=held)),
                        hx.scene.scene_text(hexapod_held(gait="wave", scale=10, period=0.6)))
    # a leg at the built-in speed: the built-in period exactly, so the tabulated loads
    default_speed = tripod.walking_speed(PERIOD, 20.0)
    assert tripod.period_for_speed(default_speed, 20.0) == PERIOD
    assert hx.scene.scene_text(front_leg_walking(speed=default_speed)) \
        == hx.scene.scene_text(front_leg_walking())


# ------------------------------------------------------------------ payload


def test_a_payload_adds_its_mass_and_its_weight_to_the_ground_reactions(walks):
    model, result = walks["default"]
    loaded, loaded_result = walks["payload"]
    assert loaded.total_mass - model.total_mass == pytest.approx(PAYLOAD, rel=1e-12)
    trunk = loaded.bodies[loaded.body_index["trunk"]]
    nominal = model.bodies[model.body_index["trunk"]]
    assert np.array_equal(trunk.inertia, nominal.inertia)  # a point mass at the centre of mass
    weight = loaded.total_mass * float(np.linalg.norm(loaded.gravity))
    for m, r in ((model, result), (loaded, loaded_result)):
        inertial, ground, _ = body_motion_balance(m, r)
        assert np.abs(ground - inertial).max() < 1e-9 * weight  # sum GR = sum m (a - g)
    # the motion is prescribed, so the payload changes the reactions by payload (a - g) alone
    _, ground, _ = body_motion_balance(model, result)
    _, loaded_ground, trunk_acceleration = body_motion_balance(loaded, loaded_result)
    assert np.abs(loaded_result.q - result.q).max() < 1e-12  # the same motion
    change = PAYLOAD * (trunk_acceleration - loaded.gravity)
    assert np.abs(loaded_ground - ground - change).max() < 1e-9 * weight
    # which, vertically, is about the payload's weight (the trunk bobs a little)
    assert (loaded_ground - ground)[:, 2] == pytest.approx(PAYLOAD * 9.81, rel=0.05)


def test_the_held_robot_loads_its_feet_with_the_payload_too():
    """The held robot's trunk is welded (the payload moves nothing), but its feet's ``sin^2``
    loads carry the robot's weight, payload included: on average over a stride, and each in
    proportion at every instant."""
    plain, loaded = hexapod_held(), hexapod_held(payload=PAYLOAD)
    assert loaded.bodies["trunk"].mass - plain.bodies["trunk"].mass \
        == pytest.approx(PAYLOAD, rel=1e-12)
    t = np.arange(2000) * PERIOD / 2000

    def vertical(scene):
        return sum(f.force[2](t) for f in scene.forces.values())

    mass = sum(b.mass for b in loaded.bodies.values())
    assert mass == pytest.approx(robot_mass(payload=PAYLOAD), rel=1e-12)
    assert vertical(loaded).mean() == pytest.approx(mass * 9.81, rel=1e-4)
    ratio = robot_mass(payload=PAYLOAD) / robot_mass()
    assert np.allclose(vertical(loaded), ratio * vertical(plain), rtol=1e-12,
                       atol=1e-12 * mass * 9.81)


# ------------------------------------------------------------------ segment lengths


def test_segment_factors_keep_every_stance_foot_on_its_foothold(walks):
    model, result = walks["lengths"]
    times = np.arange(6) * PERIOD / 6  # every foot in stance at some of them
    result = hx.inverse_dynamics(model, times)
    assert stance_slip(model, result) < 1e-12
    assert result.max_violation < 1e-10
    inertial, ground, _ = body_motion_balance(model, result)
    assert np.abs(ground - inertial).max() < 1e-9 * model.total_mass * 9.81


def test_segment_factors_scale_masses_and_inertias_with_the_lengths(walks):
    model, _ = walks["lengths"]
    nominal, _ = walks["default"]
    factors = tuple(FACTORS[f"{s}_length"] for s in SEGMENT_NAMES)
    for leg, position in (("L1", "front"), ("R2", "middle"), ("L3", "hind")):
        for segment, factor in zip(SEGMENTS[position], factors, strict=True):
            body = model.bodies[model.body_index[f"{leg}/{segment.name}"]]
            before = nominal.bodies[nominal.body_index[f"{leg}/{segment.name}"]]
            assert body.mass == pytest.approx(factor * before.mass, rel=1e-14)
            length = segment.length_mm * 1e-3 * 20 * factor
            radius = segment.radius_mm * 1e-3 * 20
            assert body.markers["distal"].position[0] == pytest.approx(length / 2, rel=1e-14)
            moments = np.sort(np.linalg.eigvalsh(body.inertia))
            assert moments[0] == pytest.approx(body.mass * radius**2 / 2, rel=1e-12)
            assert moments[2] == pytest.approx(body.mass * (3 * radius**2 + length**2) / 12,
                                               rel=1e-12)
    assert model.total_mass == pytest.approx(robot_mass(lengths=factors), rel=1e-13)
    assert robot_mass(lengths=factors) != pytest.approx(robot_mass(), rel=1e-3)


def test_segment_factors_round_trip_through_scene_files(tmp_path):
    """Longer or shorter segments are the robot's bodies and its feet's paths (the stance lines
    from the new legs' rest feet): a scene written and read back walks the same, its efforts
    and ground forces to 1e-9 of the largest (its rotations written as angles, its legs placed
    by Newton solves from poses that differ in the last bits)."""
    scene = hexapod_walking(gait="wave", **FACTORS)
    copy = hx.read_scene(hx.write_scene(scene, tmp_path / "long-legs.toml"))
    times = np.linspace(0.0, 0.04, 3)
    written, read = (hx.inverse_dynamics(hx.assemble(s), times) for s in (scene, copy))
    for name in ("effort", "ground_force"):
        a, b = getattr(written, name), getattr(read, name)
        assert np.nanmax(np.abs(a - b)) <= 1e-9 * np.nanmax(np.abs(a)), name  # NaN: no effort
    nominal = leg_geometry("front", "L").masses[3]  # the femur's, at the cockroach's lengths
    assert copy.bodies["L1/femur"].mass == pytest.approx(FACTORS["femur_length"] * nominal,
                                                        rel=1e-14)


def test_leg_specs_name_only_the_factors_that_are_not_one():
    assert leg_spec("front") == "front"
    assert leg_spec("front", (1.0, 1.0, 1.0, 1.0)) == "front"
    spec = leg_spec("hind", (1.0, 1.2, 0.1 + 0.2, 1.0))
    assert spec == "hind femur_length=1.2 tibia_length=0.30000000000000004"
    assert parse_leg(spec) == ("hind", (1.0, 1.2, 0.1 + 0.2, 1.0))
    for bad in ("fore", "front femur=1.2", "front femur_length=x", "front tibia_length=0",
                "front tibia_length=nan", "front coxa_length=2 coxa_length=2"):
        assert FootPath(bad).problems(), bad
        with pytest.raises(ValueError):
            parse_leg(bad)


def test_an_unreachable_path_names_the_leg_and_the_factors():
    """The engine's kinematics finds the path out of reach: the message names the leg, its
    factors, where in its cycle and by how much it misses."""
    with pytest.raises(ValueError, match=r"middle leg \(.*tibia_length=0\.8.*cannot follow "
                       r"its path.*fractions of its cycle.*t = 0\.29.*out of the joints' "
                       r"reach.*foot_z"):
        hexapod_walking(tibia_length=0.8)
    with pytest.raises(ValueError, match=r"middle leg \(.*tibia_length=0\.5.*cannot follow"):
        hexapod_standing(tibia_length=0.5)


# ------------------------------------------------------------------ checks


def test_the_walking_duty_keeps_three_feet_down():
    """:meth:`GaitPattern.least_duty` against a count of the feet down on a fine grid."""
    t = np.linspace(0.0, 1.0, 6001)
    for name, pattern in GAITS.items():
        least = pattern.least_duty(3)
        for duty, enough in ((least, True), (least - 0.01, False)):
            p = replace(pattern, duty=duty)
            down = sum(p.in_stance(leg, t, 1.0).astype(int) for leg in p.lift_off)
            assert bool(down.min() >= 3) == enough, (name, duty)
        assert WALKING_DUTY[name] >= least - 1e-12
    assert GAITS["tetrapod"].least_duty(3) == pytest.approx(2 / 3, rel=1e-15)
    with pytest.raises(ValueError, match=r"duty must be a finite number in \[0\.666667, 1\) "
                                         r"\(stance fraction: the walking robot's tetrapod"):
        hexapod_walking(gait="tetrapod", duty=0.6)
    hexapod_walking(gait="tetrapod", duty=2 / 3)  # its walking duty


BAD = [
    ({"gait": "trot"}, r"gait must be one of 'tripod', 'tetrapod', 'wave'"),
    ({"period": 0.0}, r"period must be a finite number > 0 \(s"),
    ({"period": math.nan}, r"period must be a finite number > 0"),
    ({"period": "0.5"}, r"period must be a finite number > 0"),
    ({"speed": -1.0}, r"speed must be a finite number > 0 \(m/s"),
    ({"speed": math.inf}, r"speed must be a finite number > 0"),
    ({"period": 0.5, "speed": 0.8}, r"give period or speed, not both"),
    ({"duty": 1.0}, r"duty must be a finite number in [(\[]0(\.5)?, 1\)"),
    ({"duty": 0.0}, r"duty must be a finite number in [(\[]0(\.5)?, 1\)"),
    ({"scale": 0.0}, r"scale must be a finite number > 0"),
    ({"scale": -20.0}, r"scale must be a finite number > 0"),
    ({"payload": -0.1}, r"payload must be a finite number >= 0 \(kg\)"),
    ({"payload": math.inf}, r"payload must be a finite number >= 0"),
    ({"coxa_length": 0.0}, r"coxa_length must be a finite number > 0"),
    ({"femur_length": -1.0}, r"femur_length must be a finite number > 0"),
    ({"tibia_length": math.nan}, r"tibia_length must be a finite number > 0"),
    ({"tarsus_length": True}, r"tarsus_length must be a finite number > 0"),
]


@pytest.mark.parametrize("builder", [hexapod_walking, hexapod_held])
@pytest.mark.parametrize(("options", "message"), BAD)
def test_a_bad_value_raises_a_value_error_naming_the_argument(builder, options, message):
    with pytest.raises(ValueError, match=message):
        builder(**options)


@pytest.mark.parametrize(("options", "message"), [
    ({"duty": 0.4}, r"duty must be a finite number in \[0\.5, 1\) \(stance fraction: the "
                    r"walking robot's tripod gait keeps three feet or more down"),
    ({"gait": "wave", "duty": 0.45}, r"duty must be a finite number in \[0\.5, 1\).*wave"),
])
def test_the_walking_robot_needs_three_feet_down(options, message):
    with pytest.raises(ValueError, match=message):
        hexapod_walking(**options)


@pytest.mark.parametrize(("builder", "options", "message"), [
    (hexapod_standing, {"feet": 7}, r"feet must be 3 to 6"),
    (hexapod_standing, {"feet": 4.5}, r"feet must be 3 to 6"),
    (hexapod_standing, {"payload": -1.0}, r"payload must be a finite number >= 0"),
    (hexapod_standing, {"scale": math.nan}, r"scale must be a finite number > 0"),
    (hexapod_standing, {"tarsus_length": 0}, r"tarsus_length must be a finite number > 0"),
    (front_leg_walking, {"gait": "gallop"}, r"gait must be one of"),
    (middle_leg_walking, {"period": -0.5}, r"period must be a finite number > 0"),
    (hind_leg_walking, {"speed": 0.0}, r"speed must be a finite number > 0"),
    (hind_leg_walking, {"speed": 1.0, "period": 0.5}, r"give period or speed, not both"),
    (front_leg_walking, {"scale": 0.0}, r"scale must be a finite number > 0"),
    (hexapod_walking, {"step_height": -0.01}, r"step_height must be a finite number > 0"),
    (hexapod_scene, {"step_height": 0.05}, r"step_height is the walking robot's"),
])
def test_the_other_builders_check_their_options(builder, options, message):
    with pytest.raises(ValueError, match=message):
        builder(**options)


def test_the_leg_scenes_take_no_option_their_loads_cannot_follow():
    """The legs' loads are the robot's ground reactions for its own duty, no payload and the
    cockroach's proportions (legs.loads): those are not options of the leg scenes."""
    for option in ("duty", "payload", *FACTORS):
        with pytest.raises(TypeError, match=option):
            front_leg_walking(**{option: 1.0})


def test_a_walking_scene_built_again_is_a_fresh_builds_copy():
    """The walking scenes are built once per process for the same arguments: each call gets a
    copy equal, element by element and law by law, to a fresh build, and an edit to one never
    reaches the next (other arguments, other scenes: the payload tests above)."""
    from hexapod.model.digest import describe
    from legs import robot

    def content(scene):
        return describe(list(scene.elements), time_laws=True)

    first = hexapod_walking(payload=0.25)
    first.bodies["trunk"].mass *= 2.0
    again = hexapod_walking(payload=0.25)
    assert again is not first and again.bodies["trunk"].mass != first.bodies["trunk"].mass
    fresh = robot._walked_scene(walking_pattern("tripod", None), PERIOD, robot.MODEL_SCALE,
                                None, "hexapod", 0.25, None, None)
    assert content(again) == content(fresh)
