"""The legs, the gaits and seed 001's formulation."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod as hx
from hexapod.inverse import inverse_dynamics, tree_plan
from legs import GAITS, front_leg_scene, hexapod_scene, leg_geometry, walking_leg_scene
from legs.gait import LEG_NAMES, leg_of
from legs.leg import JOINTS
from legs.robot import robot_mass, robot_weight
from legs.seed001 import MixedModel

PERIOD = 0.5
TIMES = np.linspace(0.0, PERIOD, 61)


def joint_values(laws, t):
    """Angles, rates and accelerations of the six joints: arrays (N, 6)."""
    values = [laws[j].evaluate(t) for j in JOINTS]
    return tuple(np.column_stack([v[k] for v in values]) for k in range(3))


# ------------------------------------------------------------------ seed 001

@pytest.mark.parametrize("loaded", [False, True])
def test_seed001_mixed_model_equals_the_engine(loaded):
    """24 unknowns, 18 rows, multipliers summed beyond each joint: the joint forces (and the
    driving torques) of the engine over a stride, to 1e-9."""
    scene = walking_leg_scene("L1") if loaded else front_leg_scene()
    result = inverse_dynamics(hx.assemble(scene), TIMES, frame="world")
    laws = GAITS["tripod"].joint_laws("L1", PERIOD)
    foot = None
    if loaded:
        foot = np.column_stack([law(TIMES) for law in GAITS["tripod"].stance_load(
            "L1", robot_weight(), PERIOD)])
        assert np.abs(foot).max() > 100  # the leg carries its share of 204 N in stance
    mixed = MixedModel(leg_geometry("front", "L"), foot_load=loaded).inverse(
        *joint_values(laws, TIMES), foot)
    assert mixed.jacobian.shape == (18, 24)
    assert np.array_equal(mixed.jacobian[:, :18], np.eye(18))
    scale = np.abs(result.force).max()
    assert np.abs(mixed.joint_forces - result.force).max() <= 1e-9 * scale
    assert np.abs(mixed.torques - result.effort).max() <= 1e-9 * np.abs(result.effort).max()


# ------------------------------------------------------------------ gaits

@pytest.mark.parametrize("gait", list(GAITS))
def test_gait_laws_are_c2(gait):
    law = GAITS[gait].joint_laws("L2", PERIOD)["fti"]
    t = np.linspace(-0.3, 1.3, 4001)
    f, fd, fdd = law.evaluate(t)
    h = 1e-6
    assert np.allclose((law(t + h) - law(t - h)) / (2 * h), fd, atol=1e-6 * np.abs(fd).max())
    assert np.allclose((law.evaluate(t + h)[1] - law.evaluate(t - h)[1]) / (2 * h), fdd,
                       atol=1e-5 * np.abs(fdd).max())
    # no jump in value, rate or acceleration across the rate switches: the one-sided limits
    # agree there to within what the third derivative allows over the 2e-9 s gap
    a, d = 1.0 - law.duty, law.blend / 2
    edges = np.array([0.0, d, a - d, a + d, 1.0 - d]) if law.duty != 0.5 else np.array([0.0])
    switches = (edges - law.shift) * law.period
    eps = 1e-9
    left, right = law.evaluate(switches - eps), law.evaluate(switches + eps)
    for k, (lo, hi) in enumerate(zip(left, right, strict=True)):
        scale = np.abs((f, fd, fdd)[k]).max()
        assert np.abs(hi - lo).max() < 1e-6 * scale, f"derivative {k} jumps at a switch"


@pytest.mark.parametrize("gait", list(GAITS))
def test_gaits_give_the_stated_phases_and_duty_factors(gait):
    pattern = GAITS[gait]
    t = np.linspace(0.0, PERIOD, 60001)[:-1]
    for leg in LEG_NAMES:
        law = pattern.phase_law(leg, PERIOD)
        lift = pattern.lift_off[leg] * PERIOD
        touch = lift + (1 - pattern.duty) * PERIOD
        phi = law.phase(np.array([lift, touch, lift + PERIOD]))[0]
        assert phi[0] % (2 * np.pi) == pytest.approx(0.0, abs=1e-12) or \
            phi[0] % (2 * np.pi) == pytest.approx(2 * np.pi, abs=1e-12)
        assert phi[1] - phi[0] == pytest.approx(np.pi, abs=1e-12)  # touch-down at pi
        assert phi[2] - phi[0] == pytest.approx(2 * np.pi, abs=1e-12)
        assert pattern.in_stance(leg, t, PERIOD).mean() == pytest.approx(pattern.duty,
                                                                          abs=1e-4)


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
            x = g.points[k] + hx.rotation_about_axis(g.axes[k], angles[k]) @ (x - g.points[k])
        return x

    h = 1e-6
    return np.column_stack([(foot(q + h * e) - foot(q - h * e)) / (2 * h) for e in np.eye(6)])


def test_stance_torques_are_the_free_torques_minus_jt_f():
    """A prescribed ground reaction f on the foot: tau = tau_free - J^T f at every sample."""
    loaded = inverse_dynamics(hx.assemble(walking_leg_scene("L1")), TIMES)
    free = inverse_dynamics(hx.assemble(front_leg_scene()), TIMES)
    force = np.column_stack([law(TIMES) for law in GAITS["tripod"].stance_load(
        "L1", robot_weight(), PERIOD)])
    laws = GAITS["tripod"].joint_laws("L1", PERIOD)
    q = joint_values(laws, TIMES)[0]
    stance = GAITS["tripod"].in_stance("L1", TIMES, PERIOD)
    assert stance.any() and (~stance).any()
    for k in range(TIMES.size):
        expected = free.effort[k] - _foot_jacobian(q[k]).T @ force[k]
        # central differences of the foot with h = 1e-6: ~1e-9 of the torques
        assert np.allclose(loaded.effort[k], expected, atol=1e-7 * (1 + np.abs(expected).max()))
    swing = ~stance
    assert np.allclose(loaded.effort[swing], free.effort[swing], atol=1e-9)


# ------------------------------------------------------------------ geometry

def test_sides_mirror_and_angles_mean_the_same_motion():
    left, right = leg_geometry("middle", "L"), leg_geometry("middle", "R")
    mirror = np.diag([1.0, -1.0, 1.0])
    assert np.allclose(right.points[6], mirror @ left.points[6])
    for g in (left, right):
        foot = np.asarray(g.points[6])
        # positive protraction moves the foot forward, positive levation raises it
        forward = np.cross(g.axes[0], foot - g.points[0])
        up = np.cross(g.axes[1], foot - g.points[1])
        assert forward[0] > 0 and up[2] > 0


def test_the_hexapod_is_a_tree_of_37_bodies_and_weighs_about_21_kg():
    model = hx.assemble(hexapod_scene())
    assert len(model.bodies) == 37 and len(model.drivers) == 36
    assert tree_plan(model) is not None
    assert robot_mass() == pytest.approx(20.8, abs=0.1)  # the note's 20:1 estimate
    result = inverse_dynamics(model, TIMES[:11])
    for leg in LEG_NAMES:
        assert leg_of(leg)[1] == leg[0]
        assert np.all(np.isfinite(result.effort[:, model.joint_index[f"{leg}/fti"]]))
