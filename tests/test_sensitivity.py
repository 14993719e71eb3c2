"""Design sensitivities (``hexapod sensitivity``): the derivatives of efforts, joint wrenches,
ground forces and figures of merit with respect to the bodies' masses and inertias.

References, each independent of the method (the saddle-point solve and policy applied to the
derivatives of the forces):

* central differences of whole runs on scenes re-read with the parameter moved (the forces
  are linear in these parameters, so the differences are exact but for round-off: 1e-6 of the
  value per relative change of the parameter is some five orders above it);
* scaling every mass and inertia of the walking robot by s scales every force by s (its only
  other forces are the ground's, which scale with them): ``sum_p p dF/dp = F``;
* the momentum of each body: the summed vertical ground forces change with a body's mass by
  ``g + a_z`` of its centre of mass, at every sample.
"""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

import hexapod as hx
from hexapod.algorithms.sensitivity import PeriodChange
from hexapod.cli import main
from hexapod.sweeps.cases import StudyError
from hexapod.sweeps.design_parameters import inertia_parameters
from hexapod.sweeps.metric_derivatives import SENSITIVE_FAMILIES, metric_sensitivities
from hexapod.sweeps.metrics import inverse_metrics
from legs.cockroach import STRIDE_PERIOD
from legs.robot import hexapod_scene
from tests.robots import walking_robot
from tests.scene_documents import SCENES

#: Relative step of the central differences.
STEP = 1e-4
#: Agreement asked, per unit relative change of the parameter, of the array's largest value.
TOLERANCE = 1e-6


def moved(scene, key: str, value: float) -> hx.Model:
    return hx.assemble(hx.sweeps.with_scene_keys(scene, {key: value}))


def central_difference(scene, change, times, evaluate):
    h = STEP * abs(change.value)  # SI; the scene key in the scene's units
    ahead, behind = (evaluate(moved(scene, change.name,
                                    (change.value + s * h) / change.scene_scale), times)
                     for s in (1.0, -1.0))
    return {k: (ahead[k] - behind[k]) / (2 * h) for k in ahead}


def forces(model, times):
    result = hx.inverse_dynamics(model, times)
    out = {"effort": result.effort, "force": result.force, "torque": result.torque}
    if model.contacts:
        out["ground_force"] = result.ground_force
    return out


@pytest.fixture(scope="module")
def front_leg():
    scene = hx.load_scene("front-leg")
    model = hx.assemble(scene)
    times = np.linspace(0.0, model.time_window()[0], 41)
    return scene, model, hx.inverse_dynamics(model, times)


@pytest.fixture(scope="module")
def front_leg_on_laws():
    """The front leg on its harmonic joint laws (``legs.front_leg_scene``), its foot loaded as
    the built-in leg's: joints moved by a parameter keep their laws (an open tree: the tree
    path's graph differentiated; the built-in leg's follow its foot's guides, through the
    phase path's step)."""
    from legs import front_leg_scene

    scene = front_leg_scene()
    scene.add(hx.load_scene("front-leg").forces["ground_reaction"])
    model = hx.assemble(scene)
    times = np.linspace(0.0, 0.5, 41)
    return scene, model, hx.inverse_dynamics(model, times)


def test_a_guided_joint_moved_against_central_differences(front_leg):
    """The built-in leg follows its foot's guides: a joint's origin moved there (on both its
    bodies: on the child it moves the point the wrench is reported about) goes through the
    phase path's step, differentiated on the scene assembled again with the shifts as
    symbols."""
    scene, model, result = front_leg
    changes = inertia_parameters(scene, ["joint.fti.origin.0", "joint.ctr.origin.2"])
    sensitivity = hx.inverse_sensitivities(model, result, changes,
                                           moved=hx.sweeps.moved_model(scene, model, changes))
    for p, change in enumerate(changes):
        h = 1e-6  # m: the forces are not linear in a length (truncation 1e-12 of them)
        ahead, behind = (forces(moved(scene, change.name, change.value + s * h), result.times)
                         for s in (1.0, -1.0))
        for name in ahead:
            value, exact = getattr(result, name), getattr(sensitivity, name)[..., p]
            reference = (ahead[name] - behind[name]) / (2 * h)
            finite = np.isfinite(value)
            assert np.abs(change.value * (exact - reference)[finite]).max() <= \
                TOLERANCE * np.abs(value[finite]).max(), (change.name, name)


def test_front_leg_against_central_differences(front_leg):
    scene, model, result = front_leg
    changes = inertia_parameters(scene, ["body.*.mass", "body.*.inertia"])
    assert len(changes) == 6 * 4  # six bodies, a mass and three moments each
    picked = [changes[k] for k in np.random.default_rng(7).choice(len(changes), 4, False)]
    picked.append(next(c for c in changes if c.name == "body.femur.inertia.1"))
    sensitivity = hx.inverse_sensitivities(model, result, picked)
    for p, change in enumerate(picked):
        reference = central_difference(scene, change, result.times, forces)
        for name, difference in reference.items():
            value = getattr(result, name)
            exact = getattr(sensitivity, name)[..., p]
            finite = np.isfinite(value)
            error = change.value * np.abs(exact[finite] - difference[finite]).max()
            assert error <= TOLERANCE * np.abs(value[finite]).max(), (change.name, name)


def test_front_leg_joint_positions_against_central_differences(front_leg_on_laws):
    """A joint's origin moves the motion itself: positions, velocities, accelerations and
    the wrenches, differentiated through the tree path's one graph (forward mode). The
    dependence is not linear: central differences of step 1e-6 m are good to some 1e-9."""
    scene, model, result = front_leg_on_laws
    changes = inertia_parameters(scene, ["joint.fti.origin", "joint.tita.origin.2"])
    sensitivity = hx.inverse_sensitivities(model, result, changes)
    for p, change in enumerate(changes):
        h = 1e-6
        ahead, behind = (hx.inverse_dynamics(moved(scene, change.name, change.value + s * h),
                                             result.times) for s in (1.0, -1.0))
        for name in ("effort", "force", "torque", "q"):
            value = getattr(result, name)
            difference = (getattr(ahead, name) - getattr(behind, name)) / (2 * h)
            exact = getattr(sensitivity, name)[..., p]
            finite = np.isfinite(value)
            error = np.abs(exact[finite] - difference[finite]).max()
            assert error <= 1e-8 * np.abs(value[finite]).max(), (change.name, name)
            assert np.abs(exact[finite]).max() > 1e-3 * np.abs(value[finite]).max()


ARM = """
[scene]
name = "arm"
dimension = 3
gravity = [0.0, -9.81, 0.0]

[[body]]
name = "upper"
mass = 1.2
inertia = [0.002, 0.03, 0.03]
com = [0.15, 0.0, 0.0]

[[body]]
name = "fore"
mass = 0.7
inertia = [0.001, 0.02, 0.02]
position = [0.3, 0.0, 0.0]
com = [0.12, 0.0, 0.0]

[[joint]]
name = "shoulder"
type = "revolute"
parent = "ground"
child = "upper"
axis = [0.0, 0.0, 1.0]

[[joint]]
name = "elbow"
type = "revolute"
parent = "upper"
child = "fore"
parent_frame = { position = [0.3, 0.0, 0.0] }
axis = [0.0, 0.0, 1.0]

[[driver]]
name = "lift"
type = "joint"
joint = "shoulder"
law = { type = "harmonic", offset = 0.2, sin = [0.5], frequency = 1.0 }

[[driver]]
name = "bend"
type = "joint"
joint = "elbow"
law = { type = "harmonic", offset = 0.6, cos = [0.4], frequency = 1.0 }
"""


def test_a_segment_length_against_central_differences(tmp_path):
    """The upper arm's length, the elbow's frame on it (``parent_frame.position.0``): the
    forearm moves out, the shoulder's torque grows."""
    path = tmp_path / "arm.toml"
    path.write_text(ARM)
    scene = hx.read_scene(path)
    model = hx.assemble(scene)
    result = hx.inverse_dynamics(model, np.linspace(0.0, 1.0, 41))
    (change,) = inertia_parameters(scene, ["joint.elbow.parent_frame.position.0"])
    assert change.value == 0.3 and list(change.parent) == [1.0, 0.0, 0.0]
    sensitivity = hx.inverse_sensitivities(model, result, [change])
    h = 1e-6
    ahead, behind = (hx.inverse_dynamics(moved(scene, change.name, 0.3 + s * h), result.times)
                     for s in (1.0, -1.0))
    for name in ("effort", "force", "q"):
        value = getattr(result, name)
        difference = (getattr(ahead, name) - getattr(behind, name)) / (2 * h)
        error = np.abs(sensitivity.__dict__[name][..., 0] - difference).max()
        assert error <= 1e-8 * np.abs(value).max(), name
    shoulder = model.joint_index["shoulder"]  # a longer arm: more torque at the shoulder
    assert np.mean(result.effort[:, shoulder] * sensitivity.effort[:, shoulder, 0]) > 0


def test_a_joint_moved_where_the_loops_cannot_follow_is_refused():
    """The robot standing on pinned feet with its joints' laws fixed: a segment's length moved
    leaves no motion (the scene moved cannot be assembled), though the rows kept by the rank
    decision would give a derivative; said, with the row left out that cannot follow (and
    without the model moved at hand, that model asked for)."""
    scene = hx.load_scene("hexapod-standing")
    model = hx.assemble(scene)
    result = hx.inverse_dynamics(model, np.array([0.0, 0.1]))
    changes = inertia_parameters(scene, ["joint.L1/tita.parent_frame.position.0"])
    with pytest.raises(hx.HexapodError, match="not an open tree.*shifted by a symbol"):
        hx.inverse_sensitivities(model, result, changes)
    with pytest.raises(hx.HexapodError, match="left out as redundant.*no motion"):
        hx.inverse_sensitivities(model, result, changes,
                                 moved=hx.sweeps.moved_model(scene, model, changes))


def test_front_leg_figures_of_merit_against_central_differences(front_leg_on_laws):
    scene, model, result = front_leg_on_laws
    changes = inertia_parameters(scene, ["body.femur.mass", "body.tibia.inertia.2",
                                         "joint.fti.origin.1"])
    sensitivity = hx.inverse_sensitivities(model, result, changes)
    derivatives = metric_sensitivities(model, result, sensitivity)
    values = inverse_metrics(model, result, SENSITIVE_FAMILIES, 1.0)
    assert {c.partition(":")[0] for c in derivatives} >= {"peak_effort", "rms_effort",
                                                           "peak_force", "energy"}

    def metrics(model, times):
        return inverse_metrics(model, hx.inverse_dynamics(model, times), SENSITIVE_FAMILIES,
                               1.0)

    for p, change in enumerate(changes):
        reference = central_difference(scene, change, result.times, metrics)
        for column, exact in derivatives.items():
            if np.isnan(values[column]):  # the leg stays put: no cost of transport
                assert np.isnan(exact[p]) and np.isnan(reference[column])
                continue
            scale = abs(values[column]) or 1.0
            assert abs(change.value * (exact[p] - reference[column])) <= TOLERANCE * scale, \
                (change.name, column)


@pytest.fixture(scope="module")
def walking():
    model = walking_robot()
    scene = hx.load_scene("hexapod")
    times = np.linspace(0.0, model.time_window()[0], 21)
    result = hx.inverse_dynamics(model, times)
    changes = inertia_parameters(scene, ["body.*.mass", "body.*.inertia"])
    return model, result, changes, hx.inverse_sensitivities(model, result, changes)


def test_walking_robot_scales_with_its_masses(walking):
    model, result, changes, sensitivity = walking
    p = np.array([c.value for c in changes])
    assert len(changes) == 4 * len(model.bodies)
    for name in ("effort", "force", "torque", "ground_force"):
        value = getattr(result, name)
        finite = np.isfinite(value)
        scaled = getattr(sensitivity, name) @ p
        assert np.abs(scaled[finite] - value[finite]).max() <= 1e-10 * np.abs(value[finite]).max()


def test_walking_figures_of_merit_scale_with_the_masses(walking):
    """Each figure of merit grows as the forces, by s (Euler's identity for a function
    homogeneous of degree 1), but the cost of transport: work over weight, of degree 0."""
    model, result, changes, sensitivity = walking
    p = np.array([c.value for c in changes])
    values = inverse_metrics(model, result, SENSITIVE_FAMILIES, 1.0)
    derivatives = metric_sensitivities(model, result, sensitivity)
    assert "cost_of_transport" in derivatives and "peak_ground:L1" in derivatives
    for column, exact in derivatives.items():
        degree = 0.0 if column == "cost_of_transport" else 1.0
        assert abs(exact @ p - degree * values[column]) <= 1e-10 * abs(values[column]), column


def test_ground_forces_follow_each_body_momentum(walking):
    model, result, changes, sensitivity = walking
    g = -model.gravity[2]
    for k, change in enumerate(changes):
        if not change.name.endswith(".mass"):
            continue
        body = model.bodies[model.body_index[change.body]]
        vertical = sensitivity.ground_force[:, :, 2, k].sum(axis=1)
        expected = g + result.v_dot[:, body.v.start + 2]
        assert np.abs(vertical - expected).max() <= 1e-10 * g, change.name


def _walking_at(period: float) -> hx.Model:
    return hx.assemble(hexapod_scene(gait="tripod", trunk="free", period=period))


@pytest.mark.slow  # three robots, 6 s: the exact identity below is the fast check, and
# bench_sensitivity checks the period at 10 random points
def test_the_gait_period_against_central_differences():
    """The period at fixed phase: the robot rebuilt with periods ``T (1 +- STEP)``, sampled at
    the same fractions of its stride, gives the derivatives of every force and figure of merit
    (the period moves no position: the motion is the same, faster or slower)."""
    period = STRIDE_PERIOD
    model = _walking_at(period)
    phases = np.linspace(0.0, 1.0, 11)
    result = hx.inverse_dynamics(model, phases * period)
    change = PeriodChange(value=period)
    sensitivity = hx.inverse_sensitivities(model, result, [change])
    assert not sensitivity.q.any()
    derivatives = metric_sensitivities(model, result, sensitivity)
    h = STEP * period

    def run(sign: float):
        moved = _walking_at(period + sign * h)
        ahead = hx.inverse_dynamics(moved, phases * (period + sign * h))
        return ahead, inverse_metrics(moved, ahead, SENSITIVE_FAMILIES, 1.0)

    (ahead, metrics_ahead), (behind, metrics_behind) = run(1.0), run(-1.0)
    for name in ("effort", "force", "torque", "ground_force"):
        value, exact = getattr(result, name), getattr(sensitivity, name)[..., 0]
        reference = (getattr(ahead, name) - getattr(behind, name)) / (2 * h)
        finite = np.isfinite(value)
        assert np.abs(period * (exact - reference)[finite]).max() <= \
            TOLERANCE * np.abs(value[finite]).max(), name
    values = inverse_metrics(model, result, SENSITIVE_FAMILIES, 1.0)
    assert {"energy", "cost_of_transport", "peak_ground:L1"} <= set(derivatives)
    for column, exact in derivatives.items():
        reference = (metrics_ahead[column] - metrics_behind[column]) / (2 * h)
        assert abs(period * (exact[0] - reference)) <= TOLERANCE * abs(values[column]), column


def test_the_period_scales_the_dynamic_forces_as_its_inverse_square():
    """Exact at fixed phase under the least-wrench policy (linear in the right-hand side, whose
    inertial and gyroscopic terms go as ``1 / T^2`` and whose weight does not): ``F(T) = F_s +
    (T0 / T)^2 (F(T0) - F_s)``, so ``T dF/dT = -2 (F - F_s)``, ``F_s`` the forces of the same
    poses held still: the robot walking a million times slower (``(1e-6)^2`` off it)."""
    period, phases = STRIDE_PERIOD, np.linspace(0.0, 1.0, 11)
    model = _walking_at(period)
    result = hx.inverse_dynamics(model, phases * period)
    still = hx.inverse_dynamics(_walking_at(1e6 * period), phases * 1e6 * period)
    sensitivity = hx.inverse_sensitivities(model, result, [PeriodChange(value=period)])
    for name in ("effort", "force", "torque", "ground_force"):
        value, static = getattr(result, name), getattr(still, name)
        exact = getattr(sensitivity, name)[..., 0]
        finite = np.isfinite(value)
        assert np.abs(period * exact + 2.0 * (value - static))[finite].max() <= \
            1e-10 * np.abs(value[finite]).max(), name


def test_a_period_the_gait_does_not_have_is_refused(walking):
    model, result, _, _ = walking
    with pytest.raises(hx.HexapodError, match="no gait of period 0.3 s.*0.5 s"):
        hx.inverse_sensitivities(model, result, [PeriodChange(value=0.3)])


def test_a_period_with_loads_of_its_own_is_refused(front_leg):
    """The front leg's ground reaction is the walking robot's at the period: its magnitude
    follows the period otherwise than by its phase (the derivative at fixed phase was 39 %
    off the central difference)."""
    scene, model, result = front_leg
    with pytest.raises(hx.HexapodError, match="forces of its own.*ground_reaction"):
        hx.inverse_sensitivities(model, result, [PeriodChange(value=0.5)])


def test_parameters_by_scene_keys():
    scene = hx.load_scene("front-leg")
    every = inertia_parameters(scene, ["body.*.mass", "body.femur.inertia.2",
                                       "body.femur.mass"])
    assert [c.name for c in every][-1] == "body.femur.inertia.2"
    assert sum(c.name == "body.femur.mass" for c in every) == 1  # named twice, kept once
    femur = scene.bodies["femur"]
    tensor = next(c for c in every if c.name == "body.femur.inertia.2").inertia
    R = femur.inertia_rotation
    assert np.allclose(tensor, R @ np.diag([0.0, 0.0, 1.0]) @ R.T, atol=1e-15)
    for bad, said in (("body.nothing*.mass", "no body matches"),
                      ("body.femur.com", "not a parameter"),
                      ("joint.tita.axis", "not a parameter"),
                      ("joint.tita.origin.3", "components 0 to 2"),
                      ("body.femur.inertia.3", "components 0 to 2")):
        with pytest.raises(StudyError, match=said):
            inertia_parameters(scene, [bad])


@pytest.fixture(scope="module")
def friction():
    """The walking robot sharing its ground forces by least effort inside pyramids of
    friction (a QP: piecewise linear in the masses, its derivative on each sample's active
    set)."""
    model = walking_robot(policy="friction")
    scene = hx.sweeps.with_scene_keys(hx.load_scene("hexapod"), {"ground.policy": "friction"})
    times = np.linspace(0.0, model.time_window()[0], 11)
    result = hx.inverse_dynamics(model, times)
    changes = inertia_parameters(scene, ["body.*.mass", "body.*.inertia"])
    return scene, model, result, changes, hx.inverse_sensitivities(model, result, changes)


def test_friction_policy_scales_with_its_masses(friction):
    """The QP's solution is positively homogeneous in the masses (its constraints are cones
    through zero): ``sum_p p dF/dp = F`` holds on every active set."""
    _, _, result, changes, sensitivity = friction
    p = np.array([c.value for c in changes])
    assert sensitivity.active_set_changes.size  # feet load and unload over the stride
    for name in ("effort", "ground_force"):
        value = getattr(result, name)
        finite = np.isfinite(value)
        scaled = getattr(sensitivity, name) @ p
        assert np.abs(scaled[finite] - value[finite]).max() <= 1e-10 * np.abs(value[finite]).max()


def test_friction_policy_against_central_differences(friction):
    scene, _, result, changes, sensitivity = friction
    k = next(i for i, c in enumerate(changes) if c.name == "body.L2/femur.mass")
    reference = central_difference(scene, changes[k], result.times, forces)
    for name in ("effort", "ground_force"):
        value = getattr(result, name)
        finite = np.isfinite(value)
        error = np.abs(getattr(sensitivity, name)[..., k][finite] - reference[name][finite])
        # the QP's solutions (DAQP) hold some 1e-12 of the weight: their differences 1e-8
        assert changes[k].value * error.max() <= TOLERANCE * np.abs(value[finite]).max(), name


def test_friction_coefficient_against_central_differences(friction):
    """``ground.mu`` moves the friction pyramids' faces: the forces follow on the active set
    (zero derivative where no face is active)."""
    scene, model, result, _, _ = friction
    (change,) = inertia_parameters(scene, ["ground.mu"])
    assert change.value == model.ground.mu
    sensitivity = hx.inverse_sensitivities(model, result, [change])
    reference = central_difference(scene, change, result.times, forces)
    for name in ("effort", "ground_force"):
        value = getattr(result, name)
        finite = np.isfinite(value)
        exact = getattr(sensitivity, name)[..., 0][finite]
        error = np.abs(exact - reference[name][finite]).max()
        assert change.value * error <= TOLERANCE * np.abs(value[finite]).max(), name
        assert change.value * np.abs(exact).max() > 0.1 * np.abs(value[finite]).max()


def test_exact_cone_is_refused():
    model = walking_robot(policy="friction", faces=0)
    result = hx.inverse_dynamics(model, np.linspace(0.0, 0.01, 3))
    changes = inertia_parameters(hx.load_scene("hexapod"), ["body.trunk.mass"])
    with pytest.raises(hx.HexapodError, match="exact cone"):
        hx.inverse_sensitivities(model, result, changes)


def test_command_writes_the_table(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["sensitivity", "front-leg", "--parameters", "body.*.mass", "body.tibia.inertia",
                 "--samples", "21", "--out", str(out)]) == 0
    assert "wrote" in capsys.readouterr().out
    with open(out / "sensitivities.csv") as stream:
        rows = list(csv.DictReader(stream))
    assert list(rows[0]) == ["metric", "parameter", "value", "unit", "elasticity"]
    units = json.loads((out / "units.json").read_text())
    assert list(units["sensitivities.csv"]) == list(rows[0])
    assert {r["parameter"] for r in rows} == {"body.thc_link_1.mass", "body.thc_link_2.mass",
                                              "body.coxa.mass", "body.femur.mass",
                                              "body.tibia.mass", "body.tarsus.mass",
                                              "body.tibia.inertia.0", "body.tibia.inertia.1",
                                              "body.tibia.inertia.2"}
    row = next(r for r in rows if r["metric"] == "peak_effort:tita"
               and r["parameter"] == "body.femur.mass")
    assert row["unit"] == "N m/kg"
    inertia = next(r for r in rows if r["parameter"] == "body.tibia.inertia.0")
    assert inertia["unit"].endswith("/(kg m^2)")
    assert (out / "tornado-peak_effort.png").stat().st_size > 0
    assert "peak_effort" in (out / "summary.md").read_text()


def test_command_derives_by_the_gait_period_and_step_height(tmp_path, capsys):
    """``gait.period`` and ``step_height`` (the built-in robot's builder argument) from the
    command line: the walking robot's table, in J per s and J per m, the derivatives and
    elasticities the library gives at the same samples."""
    out = tmp_path / "out"
    assert main(["sensitivity", "hexapod", "--parameters", "gait.period", "step_height",
                 "--samples", "5", "--metrics", "energy", "--no-figures", "--out",
                 str(out)]) == 0
    with open(out / "sensitivities.csv") as stream:
        rows = {r["parameter"]: r for r in csv.DictReader(stream)}
    assert (rows["gait.period"]["unit"], rows["step_height"]["unit"]) == ("J/s", "J/m")
    model = walking_robot()
    result = hx.inverse_dynamics(model, np.linspace(0.0, model.cycle_time(), 5))
    changes = [PeriodChange(value=0.5), *inertia_parameters(hx.load_scene("hexapod"),
                                                            ["step_height"])]
    derivatives = metric_sensitivities(
        model, result, hx.inverse_sensitivities(model, result, changes), ["energy"])["energy"]
    energy = inverse_metrics(model, result, ["energy"], 1.0)["energy"]
    for change, derivative in zip(changes, derivatives, strict=True):
        row = rows[change.name]
        assert float(row["value"]) == pytest.approx(derivative, rel=1e-9)
        assert float(row["elasticity"]) == pytest.approx(change.value * derivative / energy,
                                                         rel=1e-9)
    assert main(["sensitivity", str(SCENES / "pendulum.toml"), "--parameters", "gait.period",
                 "--no-figures", "--out", str(tmp_path / "none")]) == 1
    assert "has no gait" in capsys.readouterr().err and not (tmp_path / "none").exists()


def test_command_writes_the_derivatives_per_sample(tmp_path, front_leg_on_laws):
    scene, model, result = front_leg_on_laws
    out = tmp_path / "out"
    path = hx.write_scene(scene, tmp_path / "front-leg.toml")
    assert main(["sensitivity", str(path), "--parameters", "body.femur.mass",
                 "joint.fti.origin.2", "--samples", str(result.times.size), "--per-sample",
                 "--no-figures", "--out", str(out)]) == 0
    changes = inertia_parameters(scene, ["body.femur.mass", "joint.fti.origin.2"])
    sensitivity = hx.inverse_sensitivities(model, result, changes)
    with np.load(out / "derivatives.npz") as saved:
        assert list(saved["parameters"]) == [c.name for c in changes]
        assert list(saved["parameter_units"]) == ["kg", "m"]
        assert np.array_equal(saved["times"], result.times)
        for name in ("effort", "force", "torque", "q"):
            assert np.allclose(saved[name], getattr(sensitivity, name), rtol=1e-12,
                               atol=1e-12 * np.nanmax(np.abs(getattr(sensitivity, name))),
                               equal_nan=True), name


def test_an_infeasible_motion_is_said(tmp_path, capsys):
    """With mu = 0.2 the walking robot's feet would slip: the derivatives are computed, and
    the summary and the command say first that they are not ones to size motors by."""
    out = tmp_path / "out"
    assert main(["sensitivity", "hexapod", "--mu", "0.2", "--parameters", "body.trunk.mass",
                 "--samples", "3", "--no-figures", "--out", str(out)]) == 0
    assert "infeasible at 3 samples" in capsys.readouterr().out
    assert "**Infeasible**" in (out / "summary.md").read_text()


@pytest.mark.parametrize("args, said", [
    (["--parameters", "body.femur.length"], "not a parameter sensitivities cover"),
    (["--parameters", "body.wing.mass"], "no body matches 'wing'"),
    (["--parameters", "body.femur.mass", "--metrics", "peak_fun"], "no figure of merit"),
])
def test_bad_input_is_one_message_and_nothing_written(tmp_path, capsys, args, said):
    out = tmp_path / "out"
    assert main(["sensitivity", "front-leg", "--samples", "5", "--out", str(out), *args]) == 1
    error = capsys.readouterr().err
    assert said in error and "Traceback" not in error
    assert not out.exists()
