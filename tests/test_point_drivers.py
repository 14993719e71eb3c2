"""Coordinate drivers on a body point, in world axes or in another body's frame: the engine's
own Newton solve and velocity and acceleration equations place a limb's joints so that a point
follows a path (inverse kinematics with no limb-specific code).

Checked against the closed-form inverse kinematics of a planar two-link arm (angles, rates and
accelerations), and against the cockroach leg's own inverse kinematics (a product of
exponentials solved by Newton's method on the joint angles, :mod:`legs.stepping`): the same foot
path written as three coordinate drivers on the foot point, in the frame of a moving trunk,
gives the same motion of every body to round-off.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

import hexapod as hx
from hexapod.errors import HexapodError, ModelError
from hexapod.scene.laws import Law
from hexapod.scene.reader import read_scene
from hexapod.scene.writer import write_scene

UPPER, FORE = 0.6, 0.4  # m: the arm's links
CENTRE, RADIUS = (0.55, 0.25), 0.12  # m: the tip's circle, once round in 2 s


def tip_path(t):
    """The tip's position, velocity and acceleration on its circle (each (n, 2))."""
    w = np.pi
    c, s = np.cos(w * t), np.sin(w * t)
    return (np.column_stack([CENTRE[0] + RADIUS * c, CENTRE[1] + RADIUS * s]),
            np.column_stack([-RADIUS * w * s, RADIUS * w * c]),
            np.column_stack([-RADIUS * w * w * c, -RADIUS * w * w * s]))


def closed_form_arm(t, elbow: float = 1.0):
    """Shoulder and elbow angles (elbow up: ``theta2 > 0``; down with ``elbow = -1``), rates
    and accelerations."""
    (x, y), (xd, yd), (xdd, ydd) = (p.T for p in tip_path(t))
    c2 = (x * x + y * y - UPPER**2 - FORE**2) / (2 * UPPER * FORE)
    th2 = elbow * np.arccos(c2)
    th1 = np.arctan2(y, x) - np.arctan2(FORE * np.sin(th2), UPPER + FORE * np.cos(th2))
    s1, c1, s12, c12 = np.sin(th1), np.cos(th1), np.sin(th1 + th2), np.cos(th1 + th2)
    J = np.array([[-UPPER * s1 - FORE * s12, -FORE * s12],
                  [UPPER * c1 + FORE * c12, FORE * c12]]).transpose(2, 0, 1)
    rates = np.linalg.solve(J, np.column_stack([xd, yd])[..., None])[..., 0]
    w1, w12 = rates[:, 0], rates[:, 0] + rates[:, 1]
    bias = np.column_stack([-UPPER * c1 * w1**2 - FORE * c12 * w12**2,
                            -UPPER * s1 * w1**2 - FORE * s12 * w12**2])
    accelerations = np.linalg.solve(J, (np.column_stack([xdd, ydd]) - bias)[..., None])[..., 0]
    return np.column_stack([th1, th2]), rates, accelerations


def arm_scene() -> hx.Scene:
    """The arm bent elbow up, its tip driven round the circle by two coordinate drivers on the
    tip point (``x = cx + r cos(pi t)``, ``y = cy + r sin(pi t)``)."""
    th1, th2 = closed_form_arm(np.array([0.0]))[0][0]
    scene = hx.Scene("arm-tip", 2)
    elbow = [UPPER * np.cos(th1), UPPER * np.sin(th1)]
    scene.add(hx.scene.PlanarBody("upper", 1.2, 0.04, com=[UPPER / 2, 0.0], angle=th1))
    scene.add(hx.scene.PlanarBody("fore", 0.8, 0.01, com=[FORE / 2, 0.0], position=elbow,
                                  angle=th1 + th2, markers={"tip": [FORE, 0.0]}))
    scene.add(hx.scene.Revolute("shoulder", "ground", "upper", origin=[0.0, 0.0]))
    scene.add(hx.scene.Revolute("elbow", "upper", "fore", origin=elbow))
    for axis, expression in (("x", f"{CENTRE[0]} + {RADIUS} * cos(pi * t)"),
                             ("y", f"{CENTRE[1]} + {RADIUS} * sin(pi * t)")):
        scene.add(hx.scene.CoordinateDriver(f"tip_{axis}", "fore", axis,
                                            hx.scene.Expression(expression), point="tip"))
    return scene


def test_a_tip_driven_round_a_circle_moves_the_joints_as_the_closed_form():
    times = np.linspace(0.0, 2.0, 41)
    result = hx.inverse_dynamics(hx.assemble(arm_scene()), times)
    angles, rates, accelerations = closed_form_arm(times)
    # planar coordinates per body: x, y, angle
    body_angles = result.q[:, [2, 5]]
    assert np.abs(np.unwrap(body_angles[:, 0]) - angles[:, 0]).max() < 1e-12
    assert np.abs(body_angles[:, 1] - body_angles[:, 0] - angles[:, 1]).max() < 1e-12
    assert np.abs(result.v[:, 2] - rates[:, 0]).max() < 1e-11
    assert np.abs(result.v[:, 5] - rates[:, :2].sum(axis=1)).max() < 1e-11
    # accelerations up to some 11 rad/s^2: to round-off of the solves
    assert np.abs(result.v_dot[:, 2] - accelerations[:, 0]).max() < 1e-9
    assert np.abs(result.v_dot[:, 5] - accelerations.sum(axis=1)).max() < 1e-9


def test_the_point_driver_reads_and_writes_back(tmp_path):
    scene = arm_scene()
    path = tmp_path / "arm.toml"
    write_scene(scene, path)
    again = read_scene(path)
    driver = again.drivers["tip_x"]
    assert (driver.point, driver.frame, driver.coordinate) == ("tip", "world", "x")
    times = np.linspace(0.0, 1.0, 5)
    first = hx.inverse_dynamics(hx.assemble(scene), times)
    second = hx.inverse_dynamics(hx.assemble(again), times)
    assert np.array_equal(first.q, second.q)


def test_bad_point_drivers_are_named():
    scene = arm_scene()
    scene.add(hx.scene.CoordinateDriver("bad_frame", "fore", "x", 0.1, frame="nowhere"))
    scene.add(hx.scene.CoordinateDriver("own_frame", "fore", "y", 0.1, frame="fore"))
    scene.add(hx.scene.CoordinateDriver("bad_marker", "upper", "x", 0.1, point="toe"))
    scene.add(hx.scene.CoordinateDriver("bad_angle", "upper", "angle", 0.1, point="toe"))
    scene.add(hx.scene.CoordinateDriver("planar_roll", "upper", "roll", 0.1))
    with pytest.raises(ModelError) as caught:
        scene.validate()
    text = str(caught.value)
    for expected in ("unknown body 'nowhere'", "'fore' cannot be measured in its own frame",
                     "body 'upper' has no marker 'toe'", "an angle is the body's",
                     "only a spatial body has a roll angle"):
        assert expected in text


# ------------------------------------------------------------------ the cockroach's leg


@dataclass(frozen=True, eq=False)
class _PathShape(Law):
    """``offset + factor * s(t)``, with ``s`` the foot path's fore-aft position (``which`` 0)
    or height (1) for a unit stride and lift, one cycle a second (:mod:`legs.stepping`)."""

    which: int
    duty: float
    factor: float
    offset: float = 0.0
    kind = "test-path-shape"

    def evaluate(self, t):
        from legs.stepping import foot_path_rates

        value, rate, acceleration = foot_path_rates(t, self.duty, 1.0, 1.0)[self.which]
        return (self.offset + self.factor * value, self.factor * rate,
                self.factor * acceleration)


def _moving_trunk(leg: hx.Scene) -> hx.Scene:
    """The leg hung from a trunk that turns (its own driver), in place of the ground."""
    out = hx.Scene(leg.name, 3)
    out.add(hx.scene.SpatialBody("trunk", 0.5, [1e-3, 2e-3, 2e-3]))
    out.add(hx.scene.Revolute("yaw", "ground", "trunk", origin=[0, 0, 0], axis=[0, 0, 1]))
    out.add(hx.scene.JointDriver("turn", "yaw", hx.scene.Expression("0.3 * sin(2 * t)")))
    out.attach(leg, "leg", "trunk")
    return out


def cockroach_leg(duty: float, guides: bool) -> hx.Scene:
    """The front leg on a turning trunk walking with ``duty``: three joints driven by the gait's
    laws and the foot's path as three coordinate drivers in the trunk's frame, either driving
    the foot (the three other joints free) or as guides that the three other joints follow."""
    from legs.cockroach import FOOT_LIFT_MM, GAIT_LAWS, STANCE_LENGTH_MM
    from legs.leg import leg_scene
    from legs.stepping import SOLVED_JOINTS, foot_path_rates, path_targets

    amplitude = {joint: np.radians(a) for joint, a, _ in GAIT_LAWS}
    laws = {"thc_levation": _PathShape(1, duty, amplitude["thc_levation"]),
            "coxa_rotation": _PathShape(1, duty, amplitude["coxa_rotation"]),
            "tita": _PathShape(0, duty, 2 * amplitude["tita"])}
    if guides:
        laws.update({joint: hx.scene.Guided() for joint in SOLVED_JOINTS})
    start = path_targets("front", np.array([0.0]), duty)[0]  # m, the leg's frame
    length, lift = STANCE_LENGTH_MM * 1e-3, FOOT_LIFT_MM * 1e-3
    fore_aft = foot_path_rates(0.0, duty, 1.0, 1.0)[0][0]
    foot = {"x": _PathShape(0, duty, length, float(start[0] - length * fore_aft)),
            "y": float(start[1]), "z": _PathShape(1, duty, lift, float(start[2]))}
    leg = leg_scene("front", "L", 1.0, laws, "front-ik")
    for axis, law in foot.items():  # in the sub-model's ground: the trunk, once attached
        leg.add(hx.scene.CoordinateDriver(f"foot_{axis}", "tarsus", axis, law, point="foot",
                                          frame="ground", guide=guides))
    return _moving_trunk(leg)


def test_the_foot_driven_or_guided_moves_the_cockroach_leg_alike():
    """The front leg on a trunk that moves and turns, its foot on its path by three coordinate
    drivers in the trunk's frame (one model: the phase path) or by three guides the other
    joints follow (the guides' kinematics, then the joints' twin): every body's motion is the
    same to round-off (q to 1e-12 m, v and v_dot to 1e-10 of their largest). (That the
    guided joints follow the motion the cockroach's own inverse kinematics gave, and carry
    the same efforts, is ``tests/test_cockroach_data.py``.)"""
    driven = cockroach_leg(0.6, guides=False)
    assert [d.frame for d in driven.drivers.values() if d.kind == "coordinate"] == ["trunk"] * 3
    times = np.linspace(0.0, 1.0, 121)
    first = hx.inverse_dynamics(hx.assemble(driven), times)
    second = hx.inverse_dynamics(hx.assemble(cockroach_leg(0.6, guides=True)), times)
    assert np.abs(first.q - second.q).max() < 1e-12
    for name in ("v", "v_dot"):
        a, b = getattr(first, name), getattr(second, name)
        assert np.abs(a - b).max() < 1e-10 * np.abs(b).max()


# ------------------------------------------------------------------ a body's orientation

_ANGLES = {"roll": "0.3 * sin(2 * t)", "pitch": "0.2 + 0.4 * sin(t)", "yaw": "3 * t - 1"}


def _tait_bryan(t):
    """roll, pitch, yaw and their first two derivatives at ``t`` (each (3, n))."""
    values = np.array([0.3 * np.sin(2 * t), 0.2 + 0.4 * np.sin(t), 3 * t - 1])
    rates = np.array([0.6 * np.cos(2 * t), 0.4 * np.cos(t), 3 + 0 * t])
    return values, rates


def _body_rates(t):
    """Body-axes angular velocity of ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    (phi, theta, _), (dphi, dtheta, dpsi) = _tait_bryan(t)
    return np.column_stack([
        dphi - dpsi * np.sin(theta),
        dtheta * np.cos(phi) + dpsi * np.cos(theta) * np.sin(phi),
        -dtheta * np.sin(phi) + dpsi * np.cos(theta) * np.cos(phi)])


def _rotation(roll, pitch, yaw):
    from hexapod.spatial import rotation_about_axis

    return (rotation_about_axis([0, 0, 1], yaw) @ rotation_about_axis([0, 1, 0], pitch)
            @ rotation_about_axis([1, 0, 0], roll))


def test_a_body_pose_driven_by_its_tait_bryan_angles():
    """A free body whose centre of mass and roll, pitch and yaw are driven (a trunk's pose):
    its rotation is ``Rz Ry Rx`` of the laws (yaw past +-pi), its angular velocity the closed
    form, its angular acceleration the central difference of that (step 1e-5 s: truncation
    about 1e-10, round-off 1e-11; held to 1e-8); a second body's yaw measured in the first's
    frame adds to it."""
    scene = hx.Scene("pose", 3)
    scene.add(hx.scene.SpatialBody("trunk", 2.0, [0.01, 0.02, 0.03],
                                   rotation=_rotation(0.0, 0.2, -1.0)))
    scene.add(hx.scene.SpatialBody("head", 0.5, [0.001, 0.001, 0.001],
                                   rotation=_rotation(0.0, 0.2, -0.5)))
    for body in ("trunk", "head"):
        for axis in "xyz":
            scene.add(hx.scene.CoordinateDriver(f"{body}_{axis}", body, axis, 0.1))
    for angle, expression in _ANGLES.items():
        scene.add(hx.scene.CoordinateDriver(f"trunk_{angle}", "trunk", angle,
                                            hx.scene.Expression(expression)))
        scene.add(hx.scene.CoordinateDriver(f"head_{angle}", "head", angle,
                                            0.5 if angle == "yaw" else 0.0, frame="trunk"))
    times = np.linspace(0.0, 2.0, 41)
    result = hx.inverse_dynamics(hx.assemble(scene), times)
    from hexapod.spatial import rotation_from_euler_parameters

    (roll, pitch, yaw), _ = _tait_bryan(times)
    for k in range(times.size):
        trunk = _rotation(roll[k], pitch[k], yaw[k])
        assert np.abs(np.asarray(rotation_from_euler_parameters(result.q[k, 3:7]))
                      - trunk).max() < 1e-12
        head = trunk @ _rotation(0.0, 0.0, 0.5)
        assert np.abs(np.asarray(rotation_from_euler_parameters(result.q[k, 10:14]))
                      - head).max() < 1e-12
    assert np.abs(result.v[:, 3:6] - _body_rates(times)).max() < 1e-11
    h = 1e-5
    difference = (_body_rates(times + h) - _body_rates(times - h)) / (2 * h)
    assert np.abs(result.v_dot[:, 3:6] - difference).max() < 1e-8


# ------------------------------------------------------------------ guides and guided joints


def guided_arm(guided: bool = True) -> hx.Scene:
    """The arm with its tip guided round the circle and its two joints carrying the efforts
    (``guided``), or driven by the closed-form angles written as expression laws."""
    scene = arm_scene()
    if guided:
        for driver in scene.drivers.values():
            driver.guide = True
        for joint in ("shoulder", "elbow"):
            scene.add(hx.scene.JointDriver(f"drive_{joint}", joint, hx.scene.Guided()))
        return scene
    out = hx.Scene("arm-joints", 2)
    out.add(*[e for e in scene.elements if not isinstance(e, hx.scene.CoordinateDriver)])
    th1, th2 = closed_form_arm(np.array([0.0]))[0][0]
    x = f"({CENTRE[0]} + {RADIUS} * cos(pi * t))"
    y = f"({CENTRE[1]} + {RADIUS} * sin(pi * t))"
    elbow = f"acos(({x}^2 + {y}^2 - {UPPER**2 + FORE**2}) / {2 * UPPER * FORE})"
    shoulder = f"atan2({y}, {x}) - atan2({FORE} * sin({elbow}), {UPPER} + {FORE} * cos({elbow}))"
    for joint, expression, start in (("shoulder", shoulder, th1), ("elbow", elbow, th2)):
        out.add(hx.scene.JointDriver(f"drive_{joint}", joint,
                                     hx.scene.Expression(f"{expression} - ({float(start)!r})")))
    return out


def test_guided_joints_carry_the_efforts_of_the_closed_form_motion():
    """The arm's joints, following its guided tip, carry the efforts of the same motion driven
    joint by joint with the closed-form angles (exact derivatives of the expressions): to 1e-9
    of the largest effort, every joint wrench likewise."""
    times = np.linspace(0.0, 2.0, 41)
    guided = hx.inverse_dynamics(hx.assemble(guided_arm()), times)
    driven = hx.inverse_dynamics(hx.assemble(guided_arm(False)), times)
    assert guided.joints == driven.joints
    for name in ("effort", "force", "torque", "q", "v", "v_dot"):
        a, b = getattr(guided, name), getattr(driven, name)
        assert np.abs(a - b).max() <= 1e-9 * np.abs(b).max(), name


def test_guided_coordinates_in_blocks_compiled_are_those_mapped_over_every_sample():
    """The guided joints' coordinates go in the phase path's blocks (64, then the rest's
    binary digits), compiled to C when asked: the numbers of the Function mapped over every
    sample at once (bit for bit interpreted, to round-off compiled), the coordinates
    unwrapped."""
    from hexapod.algorithms.guided import _coordinates, guided_coordinates

    model = hx.assemble(guided_arm())
    times = np.linspace(0.0, 1.0, 101)  # blocks of 64, 32, 4 and 1
    q, v, v_dot = hx.algorithms.guided.guides_motion(model, times)
    whole = [np.asarray(x.full()) for x in _coordinates(model).map(times.size)(q.T, v.T,
                                                                                 v_dot.T)]
    whole[0] = np.unwrap(whole[0], axis=1)
    interpreted = guided_coordinates(model, q, v, v_dot)
    assert all(np.array_equal(a, b) for a, b in zip(interpreted, whole, strict=True))
    with hx.executing(compiled=True):
        compiled = guided_coordinates(model, q, v, v_dot)
    for a, b in zip(compiled, whole, strict=True):
        assert np.abs(a - b).max() <= 1e-12 * np.abs(b).max()


def test_guides_and_guided_joints_come_together():
    scene = arm_scene()
    scene.drivers["tip_x"].guide = True
    with pytest.raises(ModelError, match="no joint driver follows them"):
        scene.validate()
    scene = guided_arm()
    for driver in scene.drivers.values():
        if isinstance(driver, hx.scene.CoordinateDriver):
            driver.guide = False
    with pytest.raises(ModelError, match="follow the guides, but the scene has none"):
        scene.validate()
    scene = guided_arm()
    scene.add(hx.scene.JointEffort("push", "elbow", hx.scene.Guided()))
    with pytest.raises(ModelError, match="only a joint driver's law may be 'guided'"):
        scene.validate()


def test_a_guided_scene_reads_back(tmp_path):
    path = tmp_path / "arm.toml"
    write_scene(guided_arm(), path)
    again = read_scene(path)
    assert again.drivers["tip_x"].guide and isinstance(again.drivers["drive_elbow"].law,
                                                      hx.scene.Guided)
    times = np.linspace(0.0, 1.0, 6)
    model = hx.assemble(again)
    result = hx.inverse_dynamics(model, times)
    reference = hx.inverse_dynamics(hx.assemble(guided_arm()), times)
    assert np.array_equal(result.effort, reference.effort)


def test_a_guided_models_joint_laws_are_its_guides_motion_at_any_time():
    """In the model each guided joint's law is the motion the guides give it, solved by the
    engine's kinematics at the times asked: the closed-form angles (counted from the joint's
    zero, the written pose), rates and accelerations at times in any order (1e-9 of their
    largest), and an analysis at an instant (the state the constraints and laws give at t)
    has the arm's tip on its circle."""
    model = hx.assemble(guided_arm())
    t = np.array([0.7, 0.1, 0.35, 1.9])
    law = {model.joints[d.joint].name: d.law for d in model.drivers if d.kind == "joint"}
    values = np.array(model.law_values(t))  # (3, n_w, 4)
    closed = closed_form_arm(t)
    for k, joint in enumerate(("shoulder", "elbow")):
        for m in range(3):
            got, want = values[m, law[joint]], closed[m][:, k]
            if m == 0:  # an angle from the joint's zero, up to whole turns
                got, want = got - got[0], want - want[0]
                got = want + np.angle(np.exp(1j * (got - want)))
            assert np.abs(got - want).max() <= 1e-9 * np.abs(closed[m]).max(), (joint, m)
    data = model.create_data()
    q, _ = hx.consistent_state(model, data, 0.35)
    th = closed_form_arm(np.array([0.35]))[0][0]
    assert abs(np.angle(np.exp(1j * (q[2] - th[0])))) < 1e-9
    assert abs(np.angle(np.exp(1j * (q[5] - q[2] - th[1])))) < 1e-9


def test_guided_laws_evaluated_one_by_one_share_one_solve_of_the_guides(monkeypatch):
    """Each guided joint's law evaluated alone at the same times (a replay's motion file)
    solves the guides once, and gives what the laws evaluated together give; other times
    solve them again."""
    from hexapod.model import guided_motion

    model = hx.assemble(guided_arm())
    solver, calls = guided_motion._SOLVER[0], []
    monkeypatch.setattr(guided_motion, "_SOLVER", [
        lambda m, t: calls.append(t.size) or solver(m, t)])
    t = np.linspace(0.0, 1.0, 7)
    together = np.array(model.law_values(t))
    guided = [d.law for d in model.drivers if d.kind == "joint"]
    for index in guided:
        values = model.laws[index].evaluate(t)
        assert all(np.array_equal(v, together[m, index]) for m, v in enumerate(values))
    assert calls == [7]
    model.laws[guided[0]].evaluate(t[:3])
    assert calls == [7, 3]


def test_a_guided_scene_simulates_its_guides_motion():
    """A simulation of the guided arm: the joints move as the guides make them (their laws
    tabulated from the guides' kinematics to a hundredth of the run's tolerance), so the tip
    stays on its circle: the closed-form angles at the saved states to 1e-7 rad (rtol 1e-8)."""
    model = hx.assemble(guided_arm())
    run = hx.simulate(model, 1.0, rtol=1e-8, atol=1e-10)
    assert run.success
    angles, _, _ = closed_form_arm(run.t)
    assert np.abs(np.unwrap(run.q[:, 2]) - angles[:, 0]).max() < 1e-7
    assert np.abs(run.q[:, 5] - run.q[:, 2] - angles[:, 1]).max() < 1e-7
    assert run.options["laws"]["tabulated"] == 2


def _arm_motion(model, t, elbow):
    """The arm's absolute coordinates, velocities and accelerations (N, n) along the tip's
    circle on the branch ``elbow`` (each planar body: its centre's x, y and its angle)."""
    th, w, a = closed_form_arm(t, elbow)
    q, v, v_dot = (np.zeros((t.size, n)) for n in (model.n_q, model.n_v, model.n_v))
    along = {"upper": (th[:, 0], w[:, 0], a[:, 0], 0.0),
             "fore": (th.sum(1), w.sum(1), a.sum(1), UPPER)}
    for name, (phi, phi_d, phi_dd, _) in along.items():
        body = model.bodies[model.body_index[name]]
        half = (UPPER if name == "upper" else FORE) / 2
        e, n = np.column_stack([np.cos(phi), np.sin(phi)]), np.column_stack(
            [-np.sin(phi), np.cos(phi)])
        e1, n1 = (np.column_stack([np.cos(th[:, 0]), np.sin(th[:, 0])]),
                  np.column_stack([-np.sin(th[:, 0]), np.cos(th[:, 0])]))
        base = (UPPER * e1, UPPER * w[:, :1] * n1,
                UPPER * (a[:, :1] * n1 - w[:, :1] ** 2 * e1)) if name == "fore" else (0, 0, 0)
        q[:, body.q] = np.column_stack([base[0] + half * e, phi])
        v[:, body.v] = np.column_stack([base[1] + half * phi_d[:, None] * n, phi_d])
        v_dot[:, body.v] = np.column_stack([base[2] + half * (phi_dd[:, None] * n - phi_d[
            :, None] ** 2 * e), phi_dd])
    return q, v, v_dot


def test_a_guided_joint_that_jumps_to_another_solution_between_samples_is_followed():
    """Between samples too far apart a Newton solve may land on the other branch of the legs'
    kinematics (the elbow down): the guides' motion is solved again through the midpoint
    where a guided coordinate changes by more than its rates and accelerations account for,
    and the motion returned stays on one branch; a motion that keeps jumping is named."""
    from hexapod.algorithms.guided import guides_motion

    model = hx.assemble(guided_arm())
    times = np.linspace(0.0, 1.0, 11)
    calls = []

    def flipping(always):
        def solve(kinematics, grid, progress=None):
            calls.append(grid.size)
            q, v, v_dot = _arm_motion(model, grid, 1.0)
            if always or grid.size == times.size:  # the elbow goes down from t = 0.5 s
                down = _arm_motion(model, grid, -1.0)
                late = grid >= 0.5
                q[late], v[late], v_dot[late] = (x[late] for x in down)
            return q, v, v_dot
        return solve

    q, v, v_dot = guides_motion(model, times, solve=flipping(False))
    assert calls == [11, 12]  # once more, through the midpoint of (0.4, 0.5)
    expected = _arm_motion(model, times, 1.0)
    for got, want in zip((q, v, v_dot), expected, strict=True):
        assert np.array_equal(got, want)
    with pytest.raises(HexapodError, match=r"joint '(shoulder|elbow)' jumps between solutions "
                                           r"of the guides near t = 0.4"):
        guides_motion(model, times, solve=flipping(True))
