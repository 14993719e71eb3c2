"""The motors' check (``hexapod report --actuators``) against a hand calculation: an arm of
mass m, its centre of mass l from a horizontal hinge, turned at a constant rate W by a motor
through a gear of ratio N. Its torque is ``tau = m g l cos(W t)`` (no acceleration), its speed
W; the motor's current ``I = tau / (N k_t)``, its electrical power ``tau W + R I^2``; over a
turn the net electrical energy is the winding's heat, ``R (m g l / (N k_t))^2 T / 2``. A DC
motor of stall torque ``tau_s`` and no-load speed ``w_0`` needs ``|tau / (N tau_s) + W N /
w_0|`` of its supply's voltage: above 1 where ``cos(W t) > (1 - W N / w_0) N tau_s / (m g
l)``."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

import hexapod as hx
from hexapod.cli import main
from hexapod.errors import InputFileError

M, L, G, W = 2.0, 0.5, 9.81, 2 * math.pi  # kg, m, m/s^2, rad/s: one turn a second
A = M * G * L  # the torque's amplitude, N m
N, KT, R = 50.0, 0.02, 0.8  # gear ratio, torque constant (N m/A), resistance (ohm)
STALL, NO_LOAD = 0.2, 4 * W * N  # at the motor: 10 N m and 4 W at the joint
TABLE = f"""
[[actuator]]
name = "geared DC motor"
joints = ["hin*"]
gear_ratio = {N}
stall_torque = {STALL}
no_load_speed = {NO_LOAD}
torque_constant = {KT}
resistance = {R}
"""


def arm_scene() -> hx.Scene:
    scene = hx.Scene("geared-arm", 3, gravity=[0.0, -G, 0.0])
    scene.add(hx.scene.SpatialBody("arm", M, [0.02] * 3, position=[L, 0.0, 0.0]))
    scene.add(hx.scene.Revolute("hinge", "ground", "arm", origin=[0.0, 0.0, 0.0],
                                axis=[0, 0, 1]))
    scene.add(hx.scene.JointDriver("drive", "hinge", hx.scene.Polynomial((0.0, W))))
    return scene


@pytest.fixture(scope="module")
def turn():
    model = hx.assemble(arm_scene())
    times = np.linspace(0.0, 1.0, 2001)
    return model, hx.inverse_dynamics(model, times)


def table(tmp_path, text: str = TABLE) -> hx.scene.ActuatorTable:
    path = tmp_path / "motors.toml"
    path.write_text(text)
    return hx.scene.read_actuators(path)


def test_a_geared_dc_motor_turning_an_arm_matches_the_hand_calculation(turn, tmp_path):
    """Current, electrical power and energies in closed form (the energies by the samples'
    trapezoidal rule: 1e-5 relative at 2001 samples a turn); the envelope left while
    ``cos(W t) > c``, from 0 to ``acos(c) / W`` and from ``1 - acos(c) / W`` to the turn's end
    (the crossings interpolated between samples: to 1e-6 s), with 1.231 of the voltage and
    ``A - N tau_s (1 - W N / w_0)`` N m beyond the line at t = 0."""
    model, result = turn
    (check,) = hx.output.check_motors(model, result, table(tmp_path))
    t = result.times
    tau = A * np.cos(W * t)
    current = tau / (N * KT)
    power = tau * W + R * current**2
    np.testing.assert_allclose(check.driver.effort, tau, rtol=0, atol=1e-12 * A)
    np.testing.assert_allclose(check.current, current, rtol=0, atol=1e-12 * current.max())
    np.testing.assert_allclose(check.electrical_power, power, rtol=0, atol=1e-11 * power.max())
    heat = R * (A / (N * KT)) ** 2 / 2  # over the one-second turn
    assert check.heat == pytest.approx(heat, rel=1e-5)
    assert check.net_energy == pytest.approx(heat, rel=1e-5)  # the weight's work nets to 0
    drawn = quad(lambda s: max(0.0, A * math.cos(W * s) * W
                               + R * (A * math.cos(W * s) / (N * KT)) ** 2), 0.0, 1.0,
                 points=[0.25, 0.75, 0.3, 0.7], limit=200)[0]
    assert check.energy == pytest.approx(drawn, rel=1e-5)
    stall, slope = N * STALL, W * N / NO_LOAD  # the joint's stall torque; W / w_0 at the joint
    c = (1 - slope) * stall / A
    first, last = check.excursions
    assert (first.start, last.end) == (0.0, 1.0)
    assert first.end == pytest.approx(math.acos(c) / W, abs=1e-6)
    assert last.start == pytest.approx(1.0 - math.acos(c) / W, abs=1e-6)
    assert first.peak_use == pytest.approx(A / stall + slope, rel=1e-12)
    assert first.at == 0.0 and first.speed_excess == 0.0
    assert first.effort_excess == pytest.approx(A - stall * (1 - slope), rel=1e-12)
    assert check.peak_use.value == pytest.approx(A / stall + slope, rel=1e-12)


def test_a_rated_envelope_is_left_where_the_torque_or_the_speed_is_beyond_it(turn, tmp_path):
    """A rated torque of ``0.75 A`` (at the joint) is exceeded near both ends of the swing,
    ``|cos(W t)| > 0.75``; a rated speed below W the whole turn, by the difference."""
    model, result = turn
    rated = TABLE.split("stall_torque")[0] + f"rated_torque = {0.75 * A / N}\n" \
        f"rated_speed = {2 * W * N}\n"
    (check,) = hx.output.check_motors(model, result, table(tmp_path, rated))
    edges = [(e.start, e.end) for e in check.excursions]
    half = math.acos(0.75) / W
    np.testing.assert_allclose(edges, [(0.0, half), (0.5 - half, 0.5 + half), (1.0 - half, 1.0)],
                               atol=1e-6)
    assert check.current is None and check.energy is None  # no torque constant given
    slow = rated.replace(f"rated_speed = {2 * W * N}", f"rated_speed = {0.5 * W * N}")
    (check,) = hx.output.check_motors(model, result, table(tmp_path, slow))
    (whole,) = check.excursions
    assert (whole.start, whole.end) == (0.0, 1.0)
    assert whole.speed_excess == pytest.approx(0.5 * W, rel=1e-12)


def test_the_report_writes_the_motors_table_figure_and_section(tmp_path, capsys):
    scene = tmp_path / "arm.toml"
    hx.write_scene(arm_scene(), scene)
    (tmp_path / "motors.toml").write_text(TABLE)
    out = tmp_path / "report"
    assert main(["report", str(scene), "--actuators", str(tmp_path / "motors.toml"),
                 "--out", str(out), "--samples", "201"]) == 0
    header = (out / "motors.csv").read_text().splitlines()[0]
    assert header == "t,use:hinge,I:hinge,P_el:hinge"
    assert (out / "motors.png").read_bytes()[:4] == b"\x89PNG"
    summary = (out / "summary.md").read_text()
    assert "## Motors" in summary and "geared DC motor" in summary
    assert "0-0.111" in summary  # the first excursion, from 0 to acos(c) / W
    assert "peak \\|speed\\|" in summary and "positive work (J)" in summary


@pytest.mark.parametrize("text, message", [
    (TABLE.replace('"hin*"', '"knee"'), "'knee' names no driven joint (driven: hinge)"),
    (TABLE.replace(f"resistance = {R}", "resistance = -1"),
     "actuator 1 ('geared DC motor'): resistance must be a non-negative number, got -1"),
    (TABLE.replace(f"no_load_speed = {NO_LOAD}\n", ""),
     "stall_torque and no_load_speed go together"),
    (TABLE.replace(f"gear_ratio = {N}", "gear = 3"), "unknown key 'gear'"),
    (TABLE + "\n[[actuator]]\nname = 'twin'\njoints = ['hinge']\nrated_torque = 1\n"
     "rated_speed = 1\n", "joint 'hinge' is driven by both geared DC motor and twin"),
    ("[[actuator]\n", "not valid TOML"),
])
def test_a_bad_actuator_table_is_one_clear_error_and_nothing_is_written(tmp_path, capsys,
                                                                        text, message):
    scene = tmp_path / "arm.toml"
    hx.write_scene(arm_scene(), scene)
    path = tmp_path / "motors.toml"
    path.write_text(text)
    out = tmp_path / "report"
    assert main(["report", str(scene), "--actuators", str(path), "--out", str(out)]) == 1
    error = capsys.readouterr().err
    assert message in error and str(path) in error and "Traceback" not in error
    assert not out.exists()


def test_the_controller_and_the_check_share_the_envelope(tmp_path):
    """The joint controller clips its torque to the band the check measures against: on the
    line at the limits, 0 where the speed reaches w_0 in the torque's direction. A table
    without entries is refused."""
    lower, upper = hx.scene.effort_limits(10.0, 4.0, np.array([-4.0, 0.0, 2.0, 4.0]))
    np.testing.assert_allclose(upper, [20.0, 10.0, 5.0, 0.0])
    np.testing.assert_allclose(lower, [0.0, -10.0, -15.0, -20.0])
    (tmp_path / "empty.toml").write_text("title = 'nothing'\n")
    with pytest.raises(InputFileError, match="no \\[\\[actuator\\]\\] entries"):
        hx.scene.read_actuators(tmp_path / "empty.toml")


def test_a_robots_motors_figure_has_a_panel_per_joint_type_and_motor(turn, tmp_path):
    """Joints named ``<leg>/<joint>`` share a panel per joint type and motor, a line per leg:
    four joints of two types on two legs make two panels of two lines."""
    import dataclasses

    model, result = turn
    (check,) = hx.output.check_motors(model, result, table(tmp_path))
    checks = [dataclasses.replace(check, driver=dataclasses.replace(check.driver, joint=name))
              for name in ("L1/ctr", "L1/fti", "R1/ctr", "R1/fti")]
    figure = hx.output.envelope_figure(checks, "robot")
    titles = sorted(ax.get_title() for ax in figure.axes)
    assert titles == ["ctr: geared DC motor", "fti: geared DC motor"]
    assert all(len(ax.get_legend().get_texts()) == 2 for ax in figure.axes)


def test_the_built_in_robots_table_gives_each_driven_joint_one_motor():
    """``data/actuators/hexapod.toml`` covers the walking robot's 36 driven joints, each
    once, and each motor in it is a DC motor by its own numbers: no-load speed = stall torque
    x resistance / torque constant^2, to the 4 digits written."""
    path = Path(__file__).resolve().parents[1] / "data" / "actuators" / "hexapod.toml"
    motors = hx.scene.read_actuators(path)
    driven = [d.joint for d in hx.load_scene("hexapod").drivers.values()
              if isinstance(d, hx.scene.JointDriver)]
    assert len(driven) == 36 and set(motors.assign(driven)) == set(driven)
    for motor in motors.actuators:
        implied = motor.stall_torque * motor.resistance / motor.torque_constant**2
        assert implied == pytest.approx(motor.no_load_speed, rel=1e-3)
