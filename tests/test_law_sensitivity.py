"""Design sensitivities with respect to parameters that change the scene's laws: the walking
robot's step height, which moves its feet's paths and so the whole motion of its legs.

References, independent of the method (the phase path's sample Function differentiated in
forward mode at the result's samples, :mod:`hexapod.algorithms.law_tangents`):

* central differences of whole runs of the robot rebuilt with the step height moved: with a
  relative step of 1e-4 their truncation error is some 1e-8 of the values (measured 1e-9),
  so 1e-6 of the largest value per unit relative change leaves a margin of 100;
* the feet's paths themselves: a foot's height moves by the swing's bump ``B(u)`` per metre of
  step height and by nothing in stance, its ground position does not move, nor the trunk
  (its pose is a guide): positions of the differentiated motion, to round-off.
"""

from __future__ import annotations

import numpy as np
import pytest

import hexapod as hx
from hexapod.cli import main
from hexapod.sweeps.cases import StudyError
from hexapod.sweeps.design_parameters import inertia_parameters
from hexapod.sweeps.metric_derivatives import SENSITIVE_FAMILIES, metric_sensitivities
from hexapod.sweeps.metrics import inverse_metrics
from legs.carried import sway_design_parameter
from legs.robot import hexapod_walking
from legs.walker import StepPath
from tests.scene_documents import SCENES

#: Relative step of the central differences.
STEP = 1e-4
#: Agreement asked, per unit relative change of the parameter, of the largest value.
TOLERANCE = 1e-6
#: The built-in robot's step height (m) and the samples: a stride, both tripods' swings.
HEIGHT = 0.05
TIMES = np.linspace(0.0, 0.5, 6)


@pytest.fixture(scope="module")
def walking():
    scene = hexapod_walking(step_height=HEIGHT)
    model = hx.assemble(scene)
    result = hx.inverse_dynamics(model, TIMES, frame="world")
    change, = inertia_parameters(scene, ["step_height"])
    return scene, model, result, change


def test_the_step_height_is_held_by_the_feet_paths(walking):
    scene, _, _, change = walking
    assert (change.name, change.unit, change.value) == ("step_height", "m", HEIGHT)
    assert {law.lift for law in change.laws} == {HEIGHT}  # each foot's vertical path
    assert all(isinstance(law, StepPath) for law in change.laws)
    assert inertia_parameters(scene, ["gait.step_height"])[0].laws == change.laws


@pytest.mark.slow  # two robots built again, 5 s; bench_sensitivity checks it at 10 points
def test_the_step_height_against_central_differences(walking):
    """Every force, effort and ground force (world axes: the joint frames turn with the
    motion), every position and every figure of merit."""
    _, model, result, change = walking
    sensitivity = hx.inverse_sensitivities(model, result, [change])
    derivatives = metric_sensitivities(model, result, sensitivity)
    h = STEP * HEIGHT

    def run(sign: float):
        moved = hx.assemble(hexapod_walking(step_height=HEIGHT + sign * h))
        ahead = hx.inverse_dynamics(moved, TIMES, frame="world")
        return ahead, inverse_metrics(moved, ahead, SENSITIVE_FAMILIES, 1.0)

    (ahead, metrics_ahead), (behind, metrics_behind) = run(1.0), run(-1.0)
    for name in ("effort", "force", "torque", "ground_force", "q"):
        value, exact = getattr(result, name), getattr(sensitivity, name)[..., 0]
        reference = (getattr(ahead, name) - getattr(behind, name)) / (2 * h)
        finite = np.isfinite(value)
        assert np.abs(HEIGHT * (exact - reference)[finite]).max() <= \
            TOLERANCE * np.abs(value[finite]).max(), name
    values = inverse_metrics(model, result, SENSITIVE_FAMILIES, 1.0)
    assert {"energy", "cost_of_transport", "peak_ground:L1"} <= set(derivatives)
    for column, exact in derivatives.items():
        reference = (metrics_ahead[column] - metrics_behind[column]) / (2 * h)
        assert abs(HEIGHT * (exact[0] - reference)) <= TOLERANCE * abs(values[column]), column


@pytest.mark.slow  # four runs of the robot, 7 s: the benchmark checks lengths at 10 points
def test_a_segment_length_of_the_walking_robot_against_central_differences(walking):
    """The left front femur's length (the ``fti`` joint's frame on the femur): its foot keeps
    its path, so the leg's joints change along the stride, and with them every force.
    Against central differences of the robot read again with the length moved, Richardson
    extrapolated from steps h and h/2 (the figures of merit depend strongly on it, an
    elasticity of 14 for the joint's RMS effort: a plain difference's error, measured
    4.6e-6 at h = 1e-5 m, falls as h^2 to a round-off floor of 6e-7 at 1e-6 m)."""
    scene, model, _, _ = walking
    times = np.linspace(0.0, 0.5, 11)  # the peaks as this check's differences were measured
    result = hx.inverse_dynamics(model, times, frame="world")
    change, = inertia_parameters(scene, ["joint.L1/fti.parent_frame.position.0"])
    sensitivity = hx.inverse_sensitivities(model, result, [change],
                                           moved=hx.sweeps.moved_model(scene, model, [change]))
    derivatives = metric_sensitivities(model, result, sensitivity)

    def run(value):
        moved = hx.assemble(hx.sweeps.with_scene_keys(scene, {change.name: value}))
        outcome = hx.inverse_dynamics(moved, times, frame="world")
        return outcome, inverse_metrics(moved, outcome, SENSITIVE_FAMILIES, 1.0)

    def difference(h, get):
        (ahead, ahead_metrics), (behind, behind_metrics) = (run(change.value + h),
                                                            run(change.value - h))
        return {k: (get(ahead, ahead_metrics, k) - get(behind, behind_metrics, k)) / (2 * h)
                for k in keys}

    def extrapolated(get):
        coarse, fine = difference(2e-5, get), difference(1e-5, get)
        return {k: (4 * fine[k] - coarse[k]) / 3 for k in keys}

    keys = ["effort", "force", "torque", "ground_force", "q", *derivatives]

    def get(outcome, metrics, key):
        return metrics[key] if key in metrics else getattr(outcome, key)

    reference = extrapolated(get)
    values = inverse_metrics(model, result, SENSITIVE_FAMILIES, 1.0)
    for name in ("effort", "force", "torque", "ground_force", "q"):
        value, exact = getattr(result, name), getattr(sensitivity, name)[..., 0]
        finite = np.isfinite(value)
        assert np.abs(change.value * (exact - reference[name])[finite]).max() <= \
            TOLERANCE * np.abs(value[finite]).max(), name
    for column, exact in derivatives.items():
        assert abs(change.value * (exact[0] - reference[column])) <= \
            TOLERANCE * abs(values[column]), column


def test_the_feet_rise_by_the_swing_bump(walking):
    """The differentiated motion puts each foot where its path's derivative says: up by the
    swing's bump ``B(u)`` per metre (the vertical path is linear in its lift), nowhere in
    stance, never sideways; the trunk, whose pose is a guide, does not move. The feet's
    positions from the bodies' (centre of mass and Euler parameters)."""
    scene, model, result, change = walking
    dq = hx.inverse_sensitivities(model, result, [change]).q[..., 0]
    trunk = model.bodies[model.body_index["trunk"]]
    assert np.abs(dq[:, trunk.q]).max() <= 1e-12
    for contact in model.contacts:
        joint = model.joints[contact.joint]
        body = model.bodies[joint.child]
        law = scene.drivers[contact.name.replace("/ground", "/z")].law
        lifted = law.evaluate(TIMES)[0] - law.start
        bump = change.laws[law].evaluate(TIMES)[0]
        assert np.allclose(lifted, law.lift * bump, rtol=0, atol=1e-15)
        moved = np.array([_point_change(result.q[k, body.q], dq[k, body.q],
                                        joint.child_frame.position)
                          for k in range(TIMES.size)])
        assert np.abs(moved[:, :2]).max() <= 1e-12, contact.name
        assert np.abs(moved[:, 2] - bump).max() <= 1e-12, contact.name
        assert bump.max() > 0.2 and (bump == 0).sum() >= 3  # a swing sampled, stances


def test_feet_in_stance_move_back_by_half_the_stride_per_unit_of_duty(walking):
    """The duty factor, stride and period kept: each stance stays centred on its foothold's
    time, so a foot down moves back by half the stride per unit of duty, a foot in swing as
    its path's derivative says (the swing stretched over a shorter time), never sideways; the
    trunk does not move (``tests/test_duty_sensitivity.py`` checks the rest)."""
    scene, model, result, _ = walking
    change, = inertia_parameters(scene, ["gait.duty"])
    assert (change.name, change.value, change.key) == ("gait.duty", 0.6, "gait.duty")
    dq = hx.inverse_sensitivities(model, result, [change]).q[..., 0]
    trunk = model.bodies[model.body_index["trunk"]]
    assert np.abs(dq[:, trunk.q]).max() <= 1e-12
    stride = scene.drivers["L1/x"].law.advance
    for contact in model.contacts:
        joint = model.joints[contact.joint]
        body = model.bodies[joint.child]
        foot = contact.name.replace("/ground", "")
        expected = np.array([change.laws[scene.drivers[f"{foot}/{axis}"].law].evaluate(
            TIMES)[0] for axis in "xz"])
        moved = np.array([_point_change(result.q[k, body.q], dq[k, body.q],
                                        joint.child_frame.position)
                          for k in range(TIMES.size)])
        assert np.abs(moved[:, 1]).max() <= 1e-12, contact.name
        assert np.abs(moved[:, [0, 2]] - expected.T).max() <= 1e-12, contact.name
        down = contact.in_stance(TIMES)
        assert down.sum() >= 2 and np.abs(moved[down, 0] + stride / 2).max() <= 1e-12


def test_the_stride_moves_the_footholds_and_the_trunk(walking):
    """The stride, period and duty kept: the trunk moves by ``t / T`` per metre of stride, a
    foot in stance by its foothold's ``lift_off - duty / 2 + k`` (its stance's index ``k``:
    each stance centred under the foot's rest position), never sideways or up; the laws
    and contacts agree on its value."""
    scene, model, result, _ = walking
    change, = inertia_parameters(scene, ["gait.stride"])
    stride = scene.drivers["L1/x"].law.advance
    assert change.value == pytest.approx(stride, rel=1e-15)
    dq = hx.inverse_sensitivities(model, result, [change]).q[..., 0]
    trunk = model.bodies[model.body_index["trunk"]]
    period = scene.drivers["L1/x"].law.period
    assert np.abs(dq[:, trunk.q.start] - TIMES / period).max() <= 1e-12
    assert np.abs(dq[:, trunk.q.start + 1:trunk.q.start + 3]).max() <= 1e-12
    for contact in model.contacts:
        joint = model.joints[contact.joint]
        body = model.bodies[joint.child]
        law = scene.drivers[contact.name.replace("/ground", "/x")].law
        moved = np.array([_point_change(result.q[k, body.q], dq[k, body.q],
                                        joint.child_frame.position)
                          for k in range(TIMES.size)])
        expected = (law.evaluate(TIMES)[0] - law.start) / law.advance + law.lift_off \
            - law.duty / 2
        assert np.abs(moved[:, 0] - expected).max() <= 1e-12, contact.name
        assert np.abs(moved[:, 1:]).max() <= 1e-12, contact.name


def test_a_frame_moved_on_its_child_against_central_differences(walking):
    """The knee's frame moved along the tibia (``child_frame``, zero in the scene): it moves
    the point the knee's wrench is reported about and the least-wrench policy weighs, and the
    characteristic length the policy divides moments by (measured on the joints' points),
    both expressions of the shift; against the robot read again with it moved by 1e-6 m, per
    0.1 m of it (a segment's length): round-off 1e-9 of the largest value. Derived with the
    geometric scale in the same model (which scales that length too)."""
    scene, model, result, _ = walking
    changes = inertia_parameters(scene, ["joint.L1/fti.child_frame.position.0",
                                         "geometric_scale"])
    change = changes[0]
    moved = hx.sweeps.moved_model(scene, model, changes)
    sensitivity = hx.inverse_sensitivities(model, result, changes, moved=moved)
    h = 1e-6
    ahead, behind = (hx.inverse_dynamics(hx.assemble(hx.sweeps.with_scene_keys(
        scene, {change.name: s * h})), TIMES, frame="world") for s in (1.0, -1.0))
    for name in ("effort", "force", "torque", "ground_force", "q"):
        value, exact = getattr(result, name), getattr(sensitivity, name)[..., 0]
        reference = (getattr(ahead, name) - getattr(behind, name)) / (2 * h)
        finite = np.isfinite(value)
        assert np.abs(0.1 * (exact - reference)[finite]).max() <= \
            TOLERANCE * np.abs(value[finite]).max(), name


def test_a_longer_femur_keeps_the_feet_on_their_paths(walking):
    """The femur's length moves the leg's joints, not its foot (a guide) nor the trunk (a
    guide): the differentiated motion keeps every foot where it was, to round-off, and the
    knee (the ``fti`` joint) moves with the femur's end, along the femur, per metre: the same
    point seen from the tibia side, which the joint's rows tie to it."""
    scene, model, result, _ = walking
    change, = inertia_parameters(scene, ["joint.L1/fti.parent_frame.position.0"])
    moved = hx.sweeps.moved_model(scene, model, [change])
    dq = hx.inverse_sensitivities(model, result, [change], moved=moved).q[..., 0]
    trunk = model.bodies[model.body_index["trunk"]]
    assert np.abs(dq[:, trunk.q]).max() <= 1e-12
    for contact in model.contacts:
        joint = model.joints[contact.joint]
        body = model.bodies[joint.child]
        moved = np.array([_point_change(result.q[k, body.q], dq[k, body.q],
                                        joint.child_frame.position)
                          for k in range(TIMES.size)])
        assert np.abs(moved).max() <= 1e-12, contact.name
    knee = model.joints[model.joint_index["L1/fti"]]
    femur, tibia = model.bodies[knee.parent], model.bodies[knee.child]
    for k in range(TIMES.size):
        on_tibia = _point_change(result.q[k, tibia.q], dq[k, tibia.q],
                                 knee.child_frame.position)
        on_femur = _point_change(result.q[k, femur.q], dq[k, femur.q],
                                 knee.parent_frame.position)
        along = _rotation(result.q[k, femur.q]) @ change.parent  # the femur's axis, world
        assert np.abs(on_tibia - (on_femur + along)).max() <= 1e-12
        assert np.abs(on_tibia).max() > 0.1  # the knee moves


def _rotation(x):
    e0, e = x[3], x[4:7]
    cross = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
    return (2 * e0**2 - 1) * np.eye(3) + 2 * (np.outer(e, e) + e0 * cross)


def _point_change(x, dx, point):
    """The change along ``dx`` of the world position of a body's ``point`` (its centre of
    mass's axes) at ``x`` (centre of mass, Euler parameters ``e0, e``): ``dr + dA point``."""
    def cross(e):
        return np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])

    e0, e, de0, de = x[3], x[4:7], dx[3], dx[4:7]
    dA = 4 * e0 * de0 * np.eye(3) + 2 * (np.outer(de, e) + np.outer(e, de) + de0 * cross(e)
                                         + e0 * cross(de))
    return dx[:3] + dA @ point


def test_the_payload_against_the_robot_rebuilt_carrying_it(walking, tmp_path):
    """The builder's payload sits at the trunk's centre of mass: the forces are linear in it
    (the motion does not move), so the robot rebuilt carrying 0.25 kg gives the derivative
    by a one-sided difference, exact to round-off (measured 1e-11 of the largest value). The
    scene records the payload (read back from its file) for the parameter's value."""
    scene, model, result, _ = walking
    change, = inertia_parameters(scene, ["payload"])
    assert (change.body, change.mass, change.value, change.unit) == ("trunk", 1.0, 0.0, "kg")
    sensitivity = hx.inverse_sensitivities(model, result, [change])
    carried = hexapod_walking(step_height=HEIGHT, payload=0.25)
    ahead = hx.inverse_dynamics(hx.assemble(carried), TIMES, frame="world")
    for name in ("effort", "force", "torque", "ground_force"):
        value, exact = getattr(result, name), getattr(sensitivity, name)[..., 0]
        finite = np.isfinite(value)
        reference = (getattr(ahead, name) - value) / 0.25
        assert np.abs(exact - reference)[finite].max() <= 1e-9 * np.abs(value[finite]).max()
    path = tmp_path / "carried.toml"
    hx.write_scene(carried, path)
    assert inertia_parameters(hx.load_scene(str(path)), ["payload"])[0].value == 0.25


def test_a_payload_is_checked_and_named():
    scene = hexapod_walking()
    scene.bodies["trunk"].payload = scene.bodies["trunk"].mass
    assert any(p.where == "payload" and "must be in [0, mass" in p.message
               for p in scene.problems())
    with pytest.raises(StudyError, match="has no body with a payload"):
        inertia_parameters(hx.load_scene(str(SCENES / "pendulum.toml")), ["payload"])


def test_a_scene_without_feet_paths_is_refused(tmp_path, capsys):
    assert main(["sensitivity", str(SCENES / "pendulum.toml"), "--parameters",
                 "gait.step_height", "--no-figures", "--out", str(tmp_path / "none")]) == 1
    error = capsys.readouterr().err
    assert "no law of scene" in error and "Traceback" not in error
    assert not (tmp_path / "none").exists()


def test_a_trunk_carried_by_two_feet_is_refused():
    """A trot's trunk sway is corrected, solved from the whole motion so that two feet carry
    it: its dependence on the gait's parameters is not derived, and said."""
    for key in ("gait.step_height", "gait.duty", "gait.period"):
        with pytest.raises(ValueError, match="two feet carry the robot"):
            sway_design_parameter((0.1, 0.2), key)
    assert sway_design_parameter((0.1, 0.2), "geometric_scale") is None


@pytest.fixture(scope="module")
def quadruped():
    """The quadruped (friction policy, a planned trunk sway) and its model."""
    scene = hx.load_scene(str(SCENES.parent / "robots" / "quadruped.toml"))
    return scene, hx.assemble(scene)


def test_the_friction_policy_along_a_segment_length_against_central_differences(quadruped):
    """The quadruped shares its ground forces by the friction policy, a QP over each foot's
    pyramid: along its left front shank's length (its knee's frame on the thigh, moving the
    legs' motion) the QP's solution is derived on its active set, whose matrices move with
    the motion (:mod:`hexapod.algorithms.friction_motion`). Against the robot read again with
    the length moved by +-1e-6 m: every effort and ground force within 1e-7 of the largest
    (measured 1e-8 at 21 samples), the active set changing between the samples named."""
    scene, model = quadruped
    assert model.ground.policy == "friction"
    times = np.linspace(0.0, model.cycle_time(), 7)
    result = hx.inverse_dynamics(model, times, frame="world")
    changes = inertia_parameters(scene, ["joint.LF_knee.parent_frame.position.2"])
    sensitivity = hx.inverse_sensitivities(model, result, changes,
                                           moved=hx.sweeps.moved_model(scene, model, changes))
    assert sensitivity.active_set_changes.size >= 3  # feet lifting and landing
    h, value = 1e-6, changes[0].value
    ahead, behind = (hx.inverse_dynamics(hx.assemble(hx.sweeps.with_scene_keys(
        scene, {changes[0].name: value + s * h})), times, frame="world") for s in (1.0, -1.0))
    for name in ("effort", "force", "ground_force", "q"):
        value_, exact = getattr(result, name), getattr(sensitivity, name)[..., 0]
        reference = (getattr(ahead, name) - getattr(behind, name)) / (2 * h)
        finite = np.isfinite(value_)
        assert np.abs(exact - reference)[finite].max() <= \
            1e-7 * np.abs(value_[finite]).max(), name


def test_friction_along_a_moving_motion_with_forces_across_joints_is_refused():
    """The friction policy weighs the wrenches of forces across joints (springs between
    bodies), whose derivative along a moving motion is not written: refused before the run."""
    from types import SimpleNamespace

    from hexapod.algorithms.sensitivity import LawChange, check_parameters

    model = SimpleNamespace(name="sprung", contacts=[object()], Q_across=object(),
                            ground=SimpleNamespace(policy="friction"))
    with pytest.raises(hx.HexapodError, match="forces across joints"):
        check_parameters(model, [LawChange("gait.duty", {}, "1", key="gait.duty")])
    model.ground.policy = "min-wrench"
    check_parameters(model, [LawChange("gait.duty", {}, "1", key="gait.duty")])


def test_a_planned_trunk_sway_refuses_the_gait_parameters(quadruped):
    """The quadruped's trunk sway is planned from its feet's paths and its period (its centre
    of pressure sees the accelerations): a derivative that held it would be wrong (its
    coefficients move with the step height), so it is refused, naming why."""
    scene, _ = quadruped
    for key in ("gait.step_height", "gait.period", "gait.duty"):
        with pytest.raises(StudyError, match="planned from the feet's schedule"):
            inertia_parameters(scene, [key])


#: The powers of the scale ``s`` by which each result grows under Froude scaling.
FROUDE = {"force": 3, "torque": 4, "ground_force": 3, "effort": 4, "peak_effort": 4,
          "rms_effort": 4, "peak_force": 3, "peak_moment": 4, "peak_ground": 3, "energy": 4,
          "cost_of_transport": 0}


def test_froude_scaling(walking):
    """Lengths times ``s``, masses times ``s^3`` (inertias ``s^5``), times times ``sqrt(s)``:
    the geometric scale's derivative and half the period's, elasticities that must sum to 3
    for every force, 4 for every torque and effort, energy per stride and peak torque, 0 for
    the cost of transport, exactly (the scale's lengths move the motion through the phase
    path's step, its masses along it; the period at fixed phase)."""
    scene, model, result, _ = walking
    changes = inertia_parameters(scene, ["geometric_scale", "gait.period"])
    moved = hx.sweeps.moved_model(scene, model, changes)
    sensitivity = hx.inverse_sensitivities(model, result, changes, moved=moved)
    period = changes[1].value
    for name in ("force", "torque", "ground_force", "effort"):
        value, derivative = getattr(result, name), getattr(sensitivity, name)
        froude = derivative[..., 0] + 0.5 * period * derivative[..., 1]
        finite = np.isfinite(value)
        assert np.abs(froude - FROUDE[name] * value)[finite].max() <= \
            1e-10 * np.abs(value[finite]).max(), name
    derivatives = metric_sensitivities(model, result, sensitivity)
    values = inverse_metrics(model, result, SENSITIVE_FAMILIES, 1.0)
    for column, derivative in derivatives.items():
        froude = derivative[0] + 0.5 * period * derivative[1]
        assert abs(froude - FROUDE[column.split(":")[0]] * values[column]) <= \
            1e-10 * abs(values[column]), column
