"""A leg with more joints than its foot needs, resolved by the posture rule (``type =
"posture"``: the joint angles nearest the rest posture, weighted, among those that put the foot
where its guides say). Checked against an independent formulation: the leg's forward
kinematics written out here with rotation matrices, its Jacobian by central differences and its
null space by an SVD (the optimality condition), and SciPy's SLSQP minimising the weighted
distance to the rest posture from another start; then a URDF quadruped with ankles walking."""

from __future__ import annotations

import numpy as np
import pytest
from robots import check_pinocchio, described_walk, foot_on_ground, momentum_gap
from scipy.optimize import minimize

import hexapod as hx
from hexapod.errors import ModelError
from hexapod.scene import (
    CoordinateDriver,
    Expression,
    Guided,
    JointDriver,
    PostureDriver,
    Revolute,
    SpatialBody,
)

#: The leg at its initial pose (all angles zero): hip abduction about x and flexion about y at
#: H, knee at K and ankle at A about y, the foot point F on the foot body.
H, K, A, F = (np.array(p) for p in ([0.0, 0.0, 0.5], [0.1, 0.0, 0.33], [0.0, 0.0, 0.16],
                                     [0.06, 0.0, 0.1]))
AXES = "xyyy"
JOINTS = ("abduction", "flexion", "knee", "ankle")
REST = np.array([0.05, 0.1, -0.2, 0.3])
WEIGHTS = np.array([1.0, 2.0, 1.0, 0.5])
#: The foot's path: about its initial point, within reach.
PATH = {"x": "0.06 + 0.03 * sin(2 * pi * t)", "y": "0.02 * sin(4 * pi * t)",
        "z": "0.1 + 0.02 * (1 - cos(2 * pi * t))"}


def _rotation(axis: str, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    if axis == "x":
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def foot(theta: np.ndarray) -> np.ndarray:
    """The foot point for the joint angles ``theta``, written out here."""
    R0, R1, R2, R3 = (_rotation(a, x) for a, x in zip(AXES, theta, strict=True))
    return H + R0 @ R1 @ ((K - H) + R2 @ ((A - K) + R3 @ (F - A)))


def leg_scene(rule: bool = True) -> hx.Scene:
    scene = hx.Scene("redundant leg")
    centres = {"hip": H, "thigh": (H + K) / 2, "shank": (K + A) / 2, "foot": (A + F) / 2}
    for name, centre in centres.items():
        scene.add(SpatialBody(name, mass=0.2, inertia=[2e-4, 2e-4, 1e-4], position=centre))
    chain = (("ground", "hip", H), ("hip", "thigh", H), ("thigh", "shank", K),
             ("shank", "foot", A))
    for joint, axis, (parent, child, at) in zip(JOINTS, AXES, chain, strict=True):
        scene.add(Revolute(joint, parent, child, origin=at,
                           axis=[1.0, 0.0, 0.0] if axis == "x" else [0.0, 1.0, 0.0]))
        scene.add(JointDriver(f"drive_{joint}", joint, Guided()))
    point = F - centres["foot"]
    for axis, text in PATH.items():
        scene.add(CoordinateDriver(f"foot/{axis}", "foot", axis, Expression(text), point=point,
                                   guide=True))
    if rule:
        scene.add(PostureDriver("foot/posture", "foot", JOINTS, REST, WEIGHTS, point=point))
    return scene


def joint_angles(model: hx.Model, q: np.ndarray) -> np.ndarray:
    """Each joint's angle from its bodies' rotations (N, 4): the child's relative to the
    parent's about the joint's axis (all frames start aligned with the world)."""
    _, rotation = hx.body_poses(model, q)
    index = model.body_index
    out = []
    for joint, axis, parent in zip(JOINTS, AXES, ("ground", "hip", "thigh", "shank"),
                                   strict=True):
        child = model.joints[model.joint_index[joint]].child
        Rp = np.eye(3) if parent == "ground" else rotation[:, index[parent]]
        R = np.einsum("nji,njk->nik", np.broadcast_to(Rp, rotation[:, child].shape),
                      rotation[:, child])
        out.append(np.arctan2(R[:, 2, 1], R[:, 1, 1]) if axis == "x"
                   else np.arctan2(R[:, 0, 2], R[:, 0, 0]))
    return np.column_stack(out)


@pytest.fixture(scope="module")
def run():
    model = hx.assemble(leg_scene())
    times = np.linspace(0.0, 1.0, 21)
    result = hx.inverse_dynamics(model, times)
    return model, times, result, joint_angles(model, result.q)


def _target(t: float) -> np.ndarray:
    w = 2 * np.pi
    return np.array([0.06 + 0.03 * np.sin(w * t), 0.02 * np.sin(2 * w * t),
                     0.1 + 0.02 * (1 - np.cos(w * t))])


def test_the_foot_is_on_its_path_at_the_weighted_nearest_posture(run):
    """At every sample the foot (by the forward kinematics written here) is on its path to
    1e-12 m, and the weighted offsets from the rest posture have no component along the
    joints' motion that leaves the foot still (central differences, SVD): 1e-8 rad."""
    _, times, _, theta = run
    for t, angles in zip(times, theta, strict=True):
        assert np.abs(foot(angles) - _target(t)).max() < 1e-12
        h = 1e-6
        J = np.column_stack([(foot(angles + h * e) - foot(angles - h * e)) / (2 * h)
                             for e in np.eye(4)])
        null = np.linalg.svd(J)[2][-1]  # the joint motion that leaves the foot still
        assert abs(null @ (WEIGHTS * (angles - REST))) < 1e-8


def test_it_is_the_minimum_scipy_finds_from_another_start(run):
    """SLSQP from the rest posture, at three samples, finds the same angles (1e-6 rad: its
    tolerance)."""
    _, times, _, theta = run
    for k in (0, 7, 15):
        target = _target(times[k])
        found = minimize(lambda x: WEIGHTS @ (x - REST) ** 2, REST, method="SLSQP",
                         constraints={"type": "eq", "fun": lambda x, at=target: foot(x) - at},
                         options={"ftol": 1e-14, "maxiter": 500})
        assert found.success
        assert np.abs(found.x - theta[k]).max() < 1e-6


def test_the_joints_carry_the_leg_and_the_rule_exerts_nothing(run):
    """The dynamics has the four joints driven by the motion found, no rule or guide; the
    hip's joint force is the leg's momentum rate less its weight (1e-9 of the weight); the
    bodies' velocities and accelerations are the rates of their solved positions and
    velocities (central differences: 1e-6 of the largest)."""
    model, times, _, _ = run
    assert [d.name for d in model.drivers] == [f"drive_{j}" for j in JOINTS]
    result = hx.inverse_dynamics(model, times, frame="world")
    rate = sum(b.mass * result.v_dot[:, b.v][:, :3] for b in model.bodies)
    weight = model.total_mass * np.asarray(model.gravity)
    hip = result.force[:, model.joint_index["abduction"]]
    assert np.abs(hip + weight - rate).max() < 1e-9 * model.total_mass * 9.81
    h = 1e-5
    around = hx.inverse_dynamics(model, [0.3 - h, 0.3, 0.3 + h])
    centres = [b.q.start + np.arange(3) for b in model.bodies]
    velocity = np.concatenate([(around.q[2, c] - around.q[0, c]) / (2 * h) for c in centres])
    linear = np.concatenate([around.v[1, b.v][:3] for b in model.bodies])
    assert np.abs(velocity - linear).max() < 1e-6 * np.abs(linear).max()
    acceleration = (around.v[2] - around.v[0]) / (2 * h)
    assert np.abs(acceleration - around.v_dot[1]).max() < 1e-6 * np.abs(around.v_dot[1]).max()


def test_without_the_rule_the_leg_is_not_decided(tmp_path):
    """The same leg without its posture rule: the guides leave a joint motion free, named."""
    with pytest.raises(hx.HexapodError, match="free"):
        hx.inverse_dynamics(hx.assemble(leg_scene(rule=False)), [0.0])


def test_a_posture_rule_is_written_read_back_and_checked(tmp_path):
    path = hx.write_scene(leg_scene(), tmp_path / "leg.toml")
    again = hx.read_scene(path)
    rule = again.drivers["foot/posture"]
    assert rule.joints == JOINTS and np.array_equal(rule.rest, REST)
    assert np.array_equal(rule.weights, WEIGHTS)
    text = path.read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace('"ankle"]', '"wrist"]'))
    with pytest.raises(ModelError, match=r"joints.*'wrist' must be a revolute joint that"):
        hx.read_scene(bad)
    bad.write_text(text.replace("[1.0, 2.0, 1.0, 0.5]", "[1.0, 2.0, 1.0, 0.0]"))
    with pytest.raises(ModelError, match="weights.*must be positive"):
        hx.read_scene(bad)


def _angle(joint, rotation) -> float:
    """Joint ``joint``'s angle from its bodies' rotations at one sample (the URDF's zero)."""
    parent = np.eye(3) if joint.parent < 0 else rotation[joint.parent]
    relative = (parent @ joint.parent_frame.rotation).T @ rotation[joint.child] \
        @ joint.child_frame.rotation
    axis = np.asarray(joint.axis, dtype=float) / np.linalg.norm(joint.axis)
    skew = relative - relative.T
    return float(np.arctan2(0.5 * axis @ [skew[2, 1], skew[0, 2], skew[1, 0]],
                            0.5 * (np.trace(relative) - 1.0)))


def test_a_robot_with_ankles_walks_at_its_weighted_nearest_posture():
    """data/robots/quadruped-ankles.toml: four joints a leg, the ankles weighted 4. Stance
    feet on their footholds (1e-12 m), the momentum balance (1e-9 of the weight), Pinocchio's
    efforts (1e-8; fixture by tests/data/make_walking_fixture.py --quadruped-ankles), and at
    every sample each leg's weighted offsets from its rest posture orthogonal to the joint
    motion that leaves its foot still (the columns a_i x (r - p_i) from the bodies' poses, the
    null space by an SVD): 1e-9 rad."""
    scene, model, result, stored = described_walk("quadruped-ankles")
    for name in ("LF", "RF", "LH", "RH"):
        position, foothold, stance = foot_on_ground(scene, model, result,
                                                    scene.joints[f"{name}/ground"])
        assert np.abs(position[stance] - foothold[stance]).max() < 1e-12
    assert momentum_gap(model, result) < 1e-9
    check_pinocchio(model, result, stored)
    rest = {"abduction": 0.0, "flexion": 0.6, "knee": -1.2, "ankle": 0.6}
    weight = {"abduction": 1.0, "flexion": 1.0, "knee": 1.0, "ankle": 4.0}
    positions, rotations = hx.body_poses(model, result.q)
    for name in ("LF", "RF", "LH", "RH"):
        joints = [model.joints[model.joint_index[f"{name}_{j}"]] for j in rest]
        contact = model.joints[model.joint_index[f"{name}/ground"]]
        for r, R in zip(positions, rotations, strict=True):
            foot = r[contact.child] + R[contact.child] @ contact.child_frame.position
            columns, offsets = [], []
            for joint, key in zip(joints, rest, strict=True):
                frame = R[joint.child] @ joint.child_frame.rotation
                pivot = r[joint.child] + R[joint.child] @ joint.child_frame.position
                columns.append(np.cross(frame @ joint.axis, foot - pivot))
                offsets.append(weight[key] * (_angle(joint, R) - rest[key]))
            null = np.linalg.svd(np.column_stack(columns))[2][-1]
            assert abs(null @ offsets) < 1e-9, name
