"""The legs, the gaits and the formulation of Dumitru, Marin and Margine."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import hexapod as hx
from hexapod.algorithms.inverse import inverse_dynamics, tree_plan
from hexapod.algorithms.kinematics import marker_trajectories
from legs import GAITS, front_leg_scene, hexapod_scene, leg_geometry, walking_leg_scene
from legs.cockroach import (
    FOOT_LIFT_MM,
    GROUND_Z_MM,
    MODEL_SCALE,
)
from legs.gait import LEG_NAMES, leg_of
from legs.leg import JOINTS, leg_scene
from legs.posing import posed
from legs.robot import WALKING_DUTY, robot_mass, robot_weight
from legs.seed001 import MixedModel

PERIOD = 0.5
RNG_SEED = 20261122
TIMES = np.linspace(0.0, PERIOD, 61)


def joint_values(model, result):
    """Angles, rates and accelerations of the six joints along an inverse run's motion: arrays
    (N, 6), from the model's laws (the guided joints': the guides' kinematics solved)."""
    values = model.law_values(result.times)
    index = {model.joints[d.joint].name: d.law for d in model.drivers if d.kind == "joint"}
    return tuple(np.column_stack([values[m][index[j]] for j in JOINTS]) for m in range(3))


# ------------------------------------------------------------ Dumitru, Marin and Margine

@pytest.mark.parametrize("loaded", [False, True])
def test_seed001_mixed_model_equals_the_engine(loaded):
    """24 unknowns, 18 rows, multipliers summed beyond each joint: the joint forces (and the
    driving torques) of the engine over a stride, to 1e-9."""
    scene = walking_leg_scene("L1") if loaded else front_leg_scene()
    model = hx.assemble(scene)
    result = inverse_dynamics(model, TIMES, frame="world")
    foot = None
    if loaded:
        foot = np.column_stack([law(TIMES)
                                for law in scene.forces["ground_reaction"].force])
        assert np.abs(foot).max() > 50  # the leg carries its share of 204 N in stance
    mixed = MixedModel(leg_geometry("front", "L"), foot_load=loaded).inverse(
        *joint_values(model, result), foot)
    assert mixed.jacobian.shape == (18, 24)
    assert np.array_equal(mixed.jacobian[:, :18], np.eye(18))
    scale = np.abs(result.force).max()
    assert np.abs(mixed.joint_forces - result.force).max() <= 1e-9 * scale
    assert np.abs(mixed.torques - result.effort).max() <= 1e-9 * np.abs(result.effort).max()


# ------------------------------------------------------------------ gaits

# The feet against the paths they are designed to follow (legs.stepping): the joint laws are
# harmonic fits of inverse-kinematics solutions, so the feet miss their paths by the fit's
# error, measured (scripts/studies/gait_paths.py) at < 1e-9 m (tripod), 1e-8 m (tetrapod) and 3e-7 m
# (wave) over a 0.26 m stride at 20:1. 2e-6 m (1e-5 of the stride) bounds them all, while a
# wrong phase, side or duty factor misses by centimetres. The stance speed likewise, to 1e-3
# (measured 1.3e-6, 1e-5 and 3e-4).
PATH_TOL = 2e-6
SPEED_RTOL = 1e-3


@pytest.mark.parametrize("gait", list(GAITS))
def test_feet_follow_their_paths_in_the_hexapod(gait):
    """The engine's feet, at every sample, are on their designed paths: on one flat ground in
    stance, for the duty factor of the cycle from each leg's stated lift-off, and lifted in
    swing; the feet in stance all move backwards at the walking speed (none slips)."""
    pattern = GAITS[gait]
    t = np.linspace(0.0, PERIOD, 241)
    h = 1e-5
    model = hx.assemble(hexapod_scene(gait))
    feet = {}
    for offset in (0.0, -h, h):
        result = inverse_dynamics(model, t + offset)
        feet[offset] = marker_trajectories(model, result.q, "foot")
    designed, speed = pattern.foot_targets(t, PERIOD), pattern.walking_speed(PERIOD)
    ground = GROUND_Z_MM * 1e-3 * MODEL_SCALE
    for leg in LEG_NAMES:
        foot = feet[0.0][f"{leg}/tarsus"]
        assert np.abs(foot - designed[leg]).max() < PATH_TOL, leg
        stance = pattern.in_stance(leg, t, PERIOD)
        assert stance.mean() == pytest.approx(pattern.duty, abs=2 / t.size)
        assert np.abs(foot[stance, 2] - ground).max() < PATH_TOL
        lift = foot[~stance, 2] - ground
        assert lift.max() == pytest.approx(FOOT_LIFT_MM * 1e-3 * MODEL_SCALE, rel=1e-3)
        velocity = (feet[h][f"{leg}/tarsus"] - feet[-h][f"{leg}/tarsus"]) / (2 * h)
        assert np.abs(velocity[stance] - [-speed, 0.0, 0.0]).max() < SPEED_RTOL * speed, leg


def test_joint_laws_are_smooth_and_periodic():
    """Rates and accelerations are the derivatives of the angles, and a stride repeats."""
    for gait in GAITS:
        for law in GAITS[gait].joint_laws("R3", PERIOD).values():
            t = np.linspace(-0.3, 1.3, 801)
            f, fd, fdd = law.evaluate(t)
            h = 1e-6
            assert np.allclose((law(t + h) - law(t - h)) / (2 * h), fd,
                               atol=1e-6 * np.abs(fd).max())
            assert np.allclose((law.evaluate(t + h)[1] - law.evaluate(t - h)[1]) / (2 * h),
                               fdd, atol=1e-5 * np.abs(fdd).max())
            assert np.allclose(law(t + PERIOD), f, atol=1e-12)


def test_swing_order():
    """Tripod: the two triangles alternate; tetrapod and wave: back to front on each side."""
    t = np.linspace(0.0, PERIOD, 24001)[:-1]
    tripod = GAITS["tripod"]
    assert np.array_equal(tripod.in_stance("L1", t), tripod.in_stance("R2", t))
    assert not np.any(tripod.in_stance("L1", t) & tripod.in_stance("R1", t))
    for name in ("tetrapod", "wave"):
        pattern = GAITS[name]
        for side in "LR":
            lifts = [pattern.lift_off[f"{side}{k}"] for k in (3, 2, 1)]
            gaps = np.diff(lifts + [lifts[0] + 1]) % 1.0
            assert np.all(gaps > 0) and gaps.sum() == pytest.approx(1.0)


# ------------------------------------------------------------------ stance

def _foot_jacobian(q, side="L"):
    """d foot / d q by composing the rest-pose joint rotations (not the engine)."""
    g = leg_geometry("front", side)

    def foot(angles):
        x = np.asarray(g.points[6])
        for k in reversed(range(6)):
            turn = hx.spatial.rotation_about_axis(g.axes[k], angles[k])
            x = g.points[k] + turn @ (x - g.points[k])
        return x

    h = 1e-6
    return np.column_stack([(foot(q + h * e) - foot(q - h * e)) / (2 * h) for e in np.eye(6)])


def test_stance_torques_are_the_free_torques_minus_jt_f():
    """A prescribed ground reaction f on the foot: tau = tau_free - J^T f at every sample."""
    scene = walking_leg_scene("L1")
    model = hx.assemble(scene)
    loaded = inverse_dynamics(model, TIMES)
    unloaded = hx.Scene(scene.name, 3)
    unloaded.add(*[e for e in scene.elements if e.name != "ground_reaction"])
    free = inverse_dynamics(hx.assemble(unloaded), TIMES)
    force = np.column_stack([law(TIMES) for law in scene.forces["ground_reaction"].force])
    q = joint_values(model, loaded)[0]
    walking = replace(GAITS["tripod"], duty=WALKING_DUTY["tripod"])
    stance = walking.in_stance("L1", TIMES, PERIOD)
    assert stance.any() and (~stance).any()
    for k in range(TIMES.size):
        expected = free.effort[k] - _foot_jacobian(q[k]).T @ force[k]
        # central differences of the foot with h = 1e-6: ~1e-9 of the torques
        assert np.allclose(loaded.effort[k], expected, atol=1e-7 * (1 + np.abs(expected).max()))
    swing = ~stance  # the kept reactions are zero in swing, and so is their interpolant
    assert np.allclose(loaded.effort[swing], free.effort[swing], atol=1e-9)


# ------------------------------------------------------------------ geometry

def test_sides_mirror_and_angles_mean_the_same_motion():
    """Equal angles move the right leg as the mirror image of the left one, whatever the angles
    (every axis mirrored as a pseudo-vector); positive protraction and levation mean forward
    and up on both sides."""
    mirror = np.diag([1.0, -1.0, 1.0])
    angles = np.random.default_rng(RNG_SEED).uniform(-0.6, 0.6, size=(20, 6))

    def foot_at(position, side, pose):
        scene = posed(leg_scene(position, side, 1.0), dict(zip(JOINTS, pose, strict=True)))
        tarsus = scene.bodies["tarsus"]
        return scene.pose("tarsus").transform_point(tarsus.markers["foot"].position)

    for position in ("front", "middle", "hind"):
        left, right = leg_geometry(position, "L"), leg_geometry(position, "R")
        for pose in angles:
            assert np.allclose(foot_at(position, "R", pose),
                               foot_at(position, "L", pose) @ mirror, atol=1e-14)
        for g in (left, right):
            foot = np.asarray(g.points[6])
            forward = np.cross(g.axes[0], foot - g.points[0])
            up = np.cross(g.axes[1], foot - g.points[1])
            assert forward[0] > 0 and up[2] > 0


def test_the_hexapod_is_a_tree_of_37_bodies_and_weighs_about_21_kg():
    model = hx.assemble(hexapod_scene())
    assert len(model.bodies) == 37 and len(model.drivers) == 36
    assert tree_plan(model) is not None
    assert robot_mass() == pytest.approx(20.8, abs=0.1)  # the 20:1 estimate of legs/cockroach.py
    result = inverse_dynamics(model, TIMES[:11])
    for leg in LEG_NAMES:
        assert leg_of(leg)[1] == leg[0]
        assert np.all(np.isfinite(result.effort[:, model.joint_index[f"{leg}/fti"]]))


@pytest.mark.parametrize("feet", [6, 3])
def test_the_standing_hexapod_holds_still_on_statically_indeterminate_feet(feet):
    """A free trunk, 36 joints held by constant drivers, ``feet`` feet pinned to the ground:
    the pose is consistent (feet on z = GROUND_Z_MM), 3 feet - 6 rows are redundant and named,
    nothing accelerates, and the feet carry the weight."""
    from legs.robot import STANDING_FEET, hexapod_standing, standing_feet

    model = hx.assemble(hexapod_standing(feet))
    data = model.create_data()
    q, v = hx.consistent_state(model, data)
    assert np.abs(q - model.q0).max() < 1e-12  # built at the standing pose
    trunk = model.bodies[model.body_index["trunk"]]
    assert np.allclose(q[trunk.q], [0, 0, 0, 1, 0, 0, 0], atol=1e-12)
    feet_at = marker_trajectories(model, q[None], "foot")
    ground = GROUND_Z_MM * 1e-3 * MODEL_SCALE
    for leg, point in standing_feet().items():
        assert point[2] == pytest.approx(ground, abs=1e-12)
        assert np.allclose(feet_at[f"{leg}/tarsus"][0], point, atol=1e-12)
    v_dot = hx.forward_dynamics(model, data, 0.0, q, v)
    assert np.abs(v_dot).max() < 1e-9
    names = [model.rows[i].name for i in data.redundant_rows]
    assert len(names) == 3 * feet - 6 and all(n for n in names)
    dof = hx.degrees_of_freedom(model, data, 0.0, q)
    assert dof["dof_with_drivers"] == 0 and dof["redundant_rows"] == names
    wrenches = hx.joint_wrenches(model, data, frame="world").as_dict()
    vertical = sum(wrenches[f"{leg}/ground"]["Fz"] for leg in STANDING_FEET[:feet])
    assert vertical == pytest.approx(robot_weight(), rel=1e-9)


def test_the_foot_paths_shapes_are_their_polynomials_bit_for_bit():
    """The swing's step and lift and their derivatives, evaluated all six at once by Horner's
    rule (what a simulation's every stage asks), are numpy's evaluation of each polynomial."""
    from legs.stepping import LIFT_RATES, STEP_RATES, _shapes

    for u in (np.linspace(0.0, 1.0, 101), np.float64(0.37), np.full((3, 4), 0.61)):
        expected = np.array([p(u) for p in STEP_RATES + LIFT_RATES])
        assert np.array_equal(_shapes(u), expected)
