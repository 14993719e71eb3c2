"""``hexapod optimize`` against closed-form optima: a lever swung about a horizontal hinge,
``theta = A sin(w t)``, with a counterweight of mass ``p`` welded at ``r`` on the other side.
Its torque is ``tau = a(t) + p b(t)``, ``a = (I_a + m_a l_a^2 + I_w) theta'' + m_a g l_a cos
theta`` and ``b = r^2 theta'' - g r cos theta``; on the samples' trapezoidal rule the RMS torque
is least at ``p* = -int(a b) / int(b^2)``, a bound on the peak torque makes an interval of ``p``
(each sample's ``abs(a + p b) <= L``), and the constrained optimum is ``p*`` clipped to it. All
computed from the closed form, not from the engine."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from hexapod.cli import main
from hexapod.sweeps.optimize import optimize, read_optimization

G, A, W = 9.81, 0.6, 2 * math.pi
M_ARM, L_ARM, I_ARM, R, I_WEIGHT = 1.0, 0.3, 0.02, 0.2, 0.001
SAMPLES = 201
LEVER = f"""
[scene]
name = "lever"
dimension = 2

[[body]]
name = "arm"
mass = {M_ARM}
inertia = {I_ARM}
com = [{L_ARM}, 0.0]

[[body]]
name = "weight"
mass = 0.5
inertia = {I_WEIGHT}
position = [{-R}, 0.0]

[[joint]]
name = "hinge"
type = "revolute"
parent = "ground"
child = "arm"

[[joint]]
name = "weld"
type = "fixed"
parent = "arm"
child = "weight"

[[driver]]
name = "swing"
type = "joint"
joint = "hinge"
law = {{ type = "harmonic", sin = [{A}], frequency = {W / (2 * math.pi)} }}
"""


def closed_form() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.linspace(0.0, 1.0, SAMPLES)
    theta, acceleration = A * np.sin(W * t), -A * W**2 * np.sin(W * t)
    a = (I_ARM + M_ARM * L_ARM**2 + I_WEIGHT) * acceleration + M_ARM * G * L_ARM * np.cos(theta)
    b = R**2 * acceleration - G * R * np.cos(theta)
    return t, a, b


def trapezoid(t, x) -> float:
    return float(np.sum((x[1:] + x[:-1]) * np.diff(t)) / 2)


def least_rms() -> float:
    t, a, b = closed_form()
    return -trapezoid(t, a * b) / trapezoid(t, b * b)


def study(tmp_path, vary: str = 'range = [0.0, 5.0]', optimize_table: str = "",
          key: str = "body.weight.mass", minimize: str = "rms_effort:hinge"):
    if not (tmp_path / "lever.toml").exists():
        (tmp_path / "lever.toml").write_text(LEVER)
    path = tmp_path / "study.toml"
    path.write_text(f"""
[study]
name = "counterweight"
scene = "lever.toml"

[vary."{key}"]
{vary}

[optimize]
minimize = "{minimize}"
{optimize_table}

[job]
samples = {SAMPLES}
""")
    return path


def test_least_rms_torque(tmp_path):
    run = optimize(read_optimization(study(tmp_path)))
    assert run.success
    assert run.optimum[0] == pytest.approx(least_rms(), rel=1e-8)
    assert run.agreement < 1e-12  # the optimum's own run gives the predicted figures


def test_an_optimum_beyond_the_bounds_stops_at_them(tmp_path):
    run = optimize(read_optimization(study(tmp_path, "range = [0.0, 0.5]\nstart = 0.1")))
    assert least_rms() > 0.5 and run.optimum[0] == pytest.approx(0.5, rel=1e-9)


def test_a_bound_on_the_peak_torque(tmp_path):
    t, a, b = closed_form()
    best = least_rms()
    limit = 0.97 * float(np.max(np.abs(a + best * b)))  # the unconstrained optimum breaks it
    ends = np.sort(np.stack([(-limit - a) / b, (limit - a) / b]), axis=0)
    low, high = ends[0].max(), ends[1].min()
    assert low < high  # a feasible interval, the least RMS outside it
    expected = min(max(best, low), high)
    path = study(tmp_path, optimize_table=f'constraints = {{ "peak_effort:*" = {{ max = '
                                          f'{limit!r} }} }}')
    run = optimize(read_optimization(path))
    assert run.success and expected != best
    assert run.optimum[0] == pytest.approx(expected, rel=1e-6)
    assert run.checked["peak_effort:hinge"] <= limit * (1 + 1e-6)


def test_the_motors_bound_the_peak_torque(tmp_path):
    """An actuator table: the hinge's motor (stall torque times its gear) bounds the peak
    torque, as the constraint above does."""
    t, a, b = closed_form()
    best = least_rms()
    limit = 0.97 * float(np.max(np.abs(a + best * b)))
    ends = np.sort(np.stack([(-limit - a) / b, (limit - a) / b]), axis=0)
    expected = min(max(best, ends[0].max()), ends[1].min())
    (tmp_path / "motors.toml").write_text(f"""
[[actuator]]
name = "hinge motor"
joints = ["hinge"]
gear_ratio = 10.0
stall_torque = {limit / 10.0!r}
no_load_speed = 1000.0
""")
    run = optimize(read_optimization(study(tmp_path, optimize_table='actuators = "motors.toml"')))
    assert run.success and [lim.pattern for lim in run.limits] == ["peak_effort:hinge"]
    assert run.optimum[0] == pytest.approx(expected, rel=1e-6)


def test_command_writes_the_optimum_and_its_report(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["optimize", str(study(tmp_path)), "--out", str(out)]) == 0
    assert "Solve_Succeeded" in capsys.readouterr().out
    with open(out / "optimum.csv") as stream:
        (row,) = list(csv.DictReader(stream))
    assert float(row["optimum"]) == pytest.approx(least_rms(), rel=1e-8)
    units = json.loads((out / "units.json").read_text())
    assert {"optimization.csv", "optimum.csv", "optimum-inverse.csv"} <= set(units)
    assert "mass = 0.97" in (out / "optimum.toml").read_text()
    assert (out / "optimum-summary.md").exists() and (out / "optimization.png").exists()


LEVER_3D = f"""
[scene]
name = "lever-3d"
dimension = 3
gravity = [0.0, {-G}, 0.0]

[[body]]
name = "arm"
mass = {M_ARM}
inertia = [0.001, {I_ARM}, {I_ARM}]
com = [{L_ARM}, 0.0, 0.0]

[[body]]
name = "weight"
mass = 0.5
inertia = [{I_WEIGHT}, {I_WEIGHT}, {I_WEIGHT}]
position = [{-R}, 0.0, 0.0]

[[joint]]
name = "hinge"
type = "revolute"
parent = "ground"
child = "arm"
axis = [0.0, 0.0, 1.0]

[[joint]]
name = "weld"
type = "fixed"
parent = "arm"
child = "weight"
parent_frame = {{ position = [{-R}, 0.0, 0.0] }}

[[driver]]
name = "swing"
type = "joint"
joint = "hinge"
law = {{ type = "harmonic", sin = [{A}], frequency = {W / (2 * math.pi)} }}
"""


def test_where_to_weld_the_counterweight(tmp_path):
    """The weight's place ``x`` on the arm (a joint's position: the motion moves with it, a
    run per evaluation): ``tau = c0 + c1 x + c2 x^2``, ``c0 = (I_a + m_a l_a^2 + I_w)
    theta'' + m_a g l_a cos theta``, ``c1 = m_w g cos theta``, ``c2 = m_w theta''``; the RMS
    torque is least where the cubic ``int (c0 + c1 x + c2 x^2)(c1 + 2 c2 x) = 0`` says."""
    t, _, _ = closed_form()
    theta, acceleration = A * np.sin(W * t), -A * W**2 * np.sin(W * t)
    c0 = (I_ARM + M_ARM * L_ARM**2 + I_WEIGHT) * acceleration + M_ARM * G * L_ARM * np.cos(theta)
    c1, c2 = 0.5 * G * np.cos(theta), 0.5 * acceleration
    cubic = [trapezoid(t, 2 * c2 * c2), trapezoid(t, 3 * c1 * c2),
             trapezoid(t, c1 * c1 + 2 * c0 * c2), trapezoid(t, c0 * c1)]
    roots = [r.real for r in np.roots(cubic) if abs(r.imag) < 1e-12 and -0.6 <= r.real <= 0]
    expected = min(roots, key=lambda x: trapezoid(t, (c0 + c1 * x + c2 * x * x) ** 2))
    (tmp_path / "lever.toml").write_text(LEVER_3D)
    path = study(tmp_path, "range = [-0.6, 0.0]", key="joint.weld.parent_frame.position.0")
    run = optimize(read_optimization(path))
    assert run.success
    assert run.optimum[0] == pytest.approx(expected, rel=1e-6)


@pytest.mark.slow  # ten runs of the walking robot, built again at each period: 20 s
def test_the_gait_period_of_least_rms_torque(tmp_path):
    """The walking robot's period that minimises a knee's RMS torque (samples at the same
    phases). At fixed phase each effort is ``s + (T0 / T)^2 d`` under the least-wrench policy
    (``s`` the same poses held still, ``d`` the rest at ``T0``: its weight does not change with
    the period, its inertial forces go as ``1 / T^2``), so on the samples' trapezoidal rule the
    RMS is least at ``(T0 / T*)^2 = -int(s d) / int(d^2)``: computed from two runs, at ``T0``
    and a million times slower, by NumPy, not by the optimiser."""
    import hexapod as hx
    from hexapod.scene.builtin import builtin_scenes

    samples, joint = 11, "L3/fti"
    builder = builtin_scenes()["hexapod"].load()
    phases = np.linspace(0.0, 1.0, samples)

    def efforts(period):
        model = hx.assemble(builder(period=period))
        result = hx.inverse_dynamics(model, phases * period)
        return result.effort[:, [j.name for j in model.joints].index(joint)]

    t0 = 0.5
    s = efforts(1e6 * t0)
    d = efforts(t0) - s
    weights = np.full(samples, 1.0)
    weights[[0, -1]] = 0.5
    expected = t0 / math.sqrt(-np.sum(weights * s * d) / np.sum(weights * d * d))
    path = tmp_path / "study.toml"
    path.write_text(f"""
[study]
name = "period"
scene = "hexapod"

[vary.period]
range = [0.3, 0.8]

[optimize]
minimize = "rms_effort:{joint}"

[job]
samples = {samples}
""")
    run = optimize(read_optimization(path))
    assert run.success and 0.3 < expected < 0.8 and abs(expected - t0) > 0.02
    assert run.optimum[0] == pytest.approx(expected, rel=1e-6)
    assert run.agreement < 1e-12


@pytest.mark.parametrize("change, said", [
    ({"key": "body.wing.mass"}, "no body matches 'wing'"),
    ({"key": "body.*.mass"}, "names one parameter"),
    ({"key": "geometric_scale"}, "vary the builder's scale"),
    ({"vary": "range = [2.0, 1.0]"}, "low must be below high"),
    ({"vary": "range = [0.0, inf]"}, "two finite numbers"),
    ({"minimize": "rms_effort:knee"}, "no figure of merit 'rms_effort:knee'"),
    ({"optimize_table": 'constraints = { "peak_ground:*" = { max = 1.0 } }'},
     "matches no figure of merit"),
])
def test_bad_study_is_one_message_and_nothing_written(tmp_path, capsys, change, said):
    out = tmp_path / "out"
    assert main(["optimize", str(study(tmp_path, **change)), "--out", str(out)]) == 1
    error = capsys.readouterr().err
    assert said in error and "Traceback" not in error
    assert not out.exists()
