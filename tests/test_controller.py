"""The joint controller (``type = "controller"`` force element) against closed forms on a
planar rod hinged at one end (``I_O = m L^2 / 3``): exact feedforward tracks the target, a
critically damped PD settles as ``1 - (1 + w t) e^(-w t)``, and a saturated actuator follows its
torque-speed line, ``w(t) = w0 (1 - e^(-T t / (I w0)))``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import hexapod
from hexapod.errors import ModelError

I_O = 1.0 / 3.0  # kg m^2: a 1 kg rod of 1 m about its end
ROD = """
[scene]
name = "servo-rod"
dimension = 2
gravity = [0.0, {gravity}]

[[body]]
name = "rod"
mass = 1.0
inertia = 0.08333333333333333
position = [0.0, 0.0]
com = [0.5, 0.0]

[[joint]]
name = "hinge"
type = "revolute"
parent = "ground"
child = "rod"

[[force]]
name = "servo"
type = "controller"
joint = "hinge"
{controller}
"""


def rod(tmp_path, controller: str, gravity: float = 0.0):
    path = tmp_path / "rod.toml"
    path.write_text(ROD.format(controller=controller, gravity=gravity))
    return hexapod.assemble(hexapod.read_scene(path))


def angle(result) -> np.ndarray:
    return result.q[:, 2]


def test_exact_feedforward_tracks_the_target_under_gravity(tmp_path):
    """``tau_ff = I_O theta_d'' + m g l cos(theta_d)`` makes the rod follow ``theta_d = 0.3
    sin(2 pi t)`` exactly from the target's state: the error stays at the integrator's."""
    model = rod(tmp_path, """
target = { type = "harmonic", sin = [0.3], frequency = 1.0 }
kp = 0.0
[force.feedforward]
type = "expression"
expression = "-I*a*w^2*sin(w*t) + m*g*l*cos(a*sin(w*t))"
constants = { I = 0.3333333333333333, a = 0.3, w = 6.283185307179586, m = 1.0, g = 9.81, l = 0.5 }
""", gravity=-9.81)
    w = 2 * np.pi
    v0 = np.array([0.0, 0.5 * 0.3 * w, 0.3 * w])  # the centre of mass moves with the rod
    result = hexapod.simulate(model, 1.0, method="dop853", rtol=1e-10, atol=1e-12, v0=v0)
    assert result.success
    assert np.max(np.abs(angle(result) - 0.3 * np.sin(w * result.t))) < 1e-8


def test_a_critically_damped_pd_settles_as_the_closed_form(tmp_path):
    """No gravity, a step target of 0.5 rad, ``kd = 2 sqrt(kp I_O)``: ``theta = 0.5 (1 - (1 +
    w t) e^(-w t))`` with ``w = sqrt(kp / I_O)``."""
    kp = 12.0
    kd = float(2 * np.sqrt(kp * I_O))
    model = rod(tmp_path, f"target = 0.5\nkp = {kp!r}\nkd = {kd!r}\n")
    result = hexapod.simulate(model, 2.0, method="dop853", rtol=1e-10, atol=1e-12)
    w = np.sqrt(kp / I_O)
    exact = 0.5 * (1 - (1 + w * result.t) * np.exp(-w * result.t))
    assert np.max(np.abs(angle(result) - exact)) < 1e-8
    # the run's tracking error, err:servo, is the angle minus the target: -0.5 (1 + w t) e^-wt
    assert result.columns()[-1] == "err:servo"
    assert np.max(np.abs(result.tracking[:, 0] - (exact - 0.5))) < 1e-8


def test_the_tracking_error_is_wrapped_and_follows_a_moving_target(tmp_path):
    """A target turning at 1 rad/s past pi, followed exactly (the state on the target): the
    error stays zero through the wrap, not 2 pi; and ``hexapod simulate`` draws it
    (``tracking.png``) beside the ``err:servo`` column."""
    from commands import in_process

    model = rod(tmp_path, "target = { type = \"polynomial\", coefficients = [3.0, 1.0] }\n"
                          "kp = 50.0\nkd = 5.0\n")
    v0 = np.array([-0.5 * np.sin(3.0), 0.5 * np.cos(3.0), 1.0])
    result = hexapod.simulate(model, 0.5, method="dop853", rtol=1e-10, atol=1e-12,
                              q0=np.array([0.5 * np.cos(3.0), 0.5 * np.sin(3.0), 3.0]), v0=v0)
    assert np.max(np.abs(result.tracking[:, 0])) < 1e-8
    done = in_process("simulate", str(tmp_path / "rod.toml"), "--t-end", "0.2", "--out",
                      "run", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "run" / "tracking.png").stat().st_size > 0
    header = (tmp_path / "run" / "results.csv").read_text().splitlines()[0]
    assert header.split(",")[-1] == "err:servo"


def test_a_saturated_actuator_follows_its_torque_speed_line(tmp_path):
    """A target 1.5 rad away and a stiff gain saturate the actuator at its upper line ``T (1 - w /
    w0)``: ``w(t) = w0 (1 - exp(-T t / (I_O w0)))`` while the error is large."""
    T, w0 = 2.0, 5.0
    model = rod(tmp_path, f"target = 1.5\nkp = 1e6\nmax_effort = {T}\nno_load_speed = {w0}\n")
    result = hexapod.simulate(model, 0.25, method="dop853", rtol=1e-10, atol=1e-12)
    exact = w0 * (1 - np.exp(-T * result.t / (I_O * w0)))
    assert np.max(np.abs(result.v[:, 2] - exact)) < 1e-8
    # and the flat limit alone: constant acceleration T / I_O
    flat = rod(tmp_path, f"target = 1.5\nkp = 1e6\nmax_effort = {T}\n")
    result = hexapod.simulate(flat, 0.25, method="dop853", rtol=1e-10, atol=1e-12)
    assert np.max(np.abs(result.v[:, 2] - T / I_O * result.t)) < 1e-8


@pytest.mark.parametrize("controller, key", [
    ("target = 0.0\nkp = -1.0\n", "kp"), ("target = 0.0\nkd = -1.0\n", "kd"),
    ("target = 0.0\nmax_effort = 0.0\n", "max_effort"),
    ("target = 0.0\nno_load_speed = 3.0\n", "no_load_speed"),
    ("target = 0.0\nmax_effort = 1.0\nno_load_speed = -3.0\n", "no_load_speed")])
def test_a_bad_controller_is_one_problem_naming_its_key(tmp_path, controller, key):
    with pytest.raises(ModelError) as info:
        rod(tmp_path, controller)
    assert len(info.value.problems) == 1
    assert "servo" in str(info.value.problems[0]) and key in str(info.value.problems[0])


@pytest.mark.parametrize("kp", [12.0, 1e6])
def test_the_contact_scheme_takes_a_stiff_controller_implicitly(kp):
    """Moreau-Jean takes state-dependent forces linearly implicit: the critically damped PD
    follows its closed form at order 1 (errors halve with the step) and, with ``kp = 1e6``
    (``w h`` up to 3.5, where a force taken at the step's start blows up), still settles on
    the target."""
    from hexapod.scene import JointController, PlanarBody, Revolute

    kd = float(2 * np.sqrt(kp * I_O))
    scene = hexapod.Scene("rod", dimension=2, gravity=[0.0, 0.0])
    scene.add(PlanarBody("rod", mass=1.0, inertia=1.0 / 12, position=[0.0, 0.0],
                         com=[0.5, 0.0]))
    scene.add(Revolute("hinge", "ground", "rod"))
    scene.add(JointController("servo", "hinge", target=0.5, kp=kp, kd=kd))
    model = hexapod.assemble(scene)
    w = np.sqrt(kp / I_O)
    errors = []
    for h in (2e-3, 1e-3):
        result = hexapod.simulate(model, 1.0, method="moreau-jean", step=h)
        assert result.success
        exact = 0.5 * (1 - (1 + w * result.t) * np.exp(-w * result.t))
        errors.append(np.max(np.abs(angle(result) - exact)))
        if kp > 1e3:
            assert abs(angle(result)[-1] - 0.5) < 1e-12
    if kp < 1e3:
        assert errors[1] < 1e-5 and 1.6 < errors[0] / errors[1] < 2.4


def test_reflected_inertias_are_the_closed_forms_and_refuse_a_loop(tmp_path):
    """The rod about its hinge: ``m L^2 / 3``. The planar double pendulum (upper rod 1 kg,
    1 m; lower 0.5 kg, 0.8 m, hanging from the tip): the shoulder sees both rods,
    ``1/12 + 1 (0.5)^2 + 0.5 (0.8)^2 / 12 + 0.5 |(1, -0.4)|^2``, the elbow the lower rod about
    its end, ``0.5 (0.8)^2 / 3``. A joint of a closed loop (the spatial four-bar) has none."""
    assert hexapod.reflected_inertias(rod(tmp_path, "target = 0.0\n"),
                                      rod(tmp_path, "target = 0.0\n").q0) == pytest.approx(
        {"hinge": I_O}, rel=1e-12)
    scenes = Path(__file__).resolve().parents[1] / "data" / "scenes"
    pendulum = hexapod.assemble(hexapod.load_scene(scenes / "double_pendulum_planar.toml"))
    inertia = hexapod.reflected_inertias(pendulum, pendulum.q0)
    shoulder = 1 / 12 + 0.25 + 0.5 * 0.64 / 12 + 0.5 * (1.0 + 0.16)
    assert inertia == pytest.approx({"shoulder": shoulder, "elbow": 0.5 * 0.64 / 3}, rel=1e-12)
    four_bar = hexapod.assemble(hexapod.load_scene(scenes / "four_bar_3d.toml"))
    with pytest.raises(hexapod.HexapodError, match="closes a loop"):
        hexapod.reflected_inertias(four_bar, four_bar.q0)


def test_the_bandwidth_option_sets_critically_damped_gains(tmp_path):
    """``hexapod simulate --bandwidth 1``: the rod's servo gets ``kp = I_O w^2`` and ``kd = 2
    I_O w`` (``w = 2 pi``; the scene's own gains, far off, are replaced), so a step target of
    0.5 rad is followed as ``0.5 (1 - (1 + w t) e^(-w t))``; a scene without controllers is
    refused by name, nothing written."""
    from commands import in_process

    rod(tmp_path, "target = 0.5\nkp = 100.0\nkd = 0.0\n")
    done = in_process("simulate", str(tmp_path / "rod.toml"), "--bandwidth", "1", "--t-end",
                      "2", "--method", "dop853", "--rtol", "1e-10", "--atol", "1e-12",
                      "--out", "run", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    run = np.load(tmp_path / "run" / "results.npz")
    w = 2 * np.pi
    exact = 0.5 * (1 - (1 + w * run["t"]) * np.exp(-w * run["t"]))
    assert np.max(np.abs(run["q"][:, 2] - exact)) < 1e-8
    plain = tmp_path / "plain.toml"
    plain.write_text(ROD.format(controller="target = 0.5", gravity=0.0)
                     .split("[[force]]")[0])
    done = in_process("simulate", str(plain), "--bandwidth", "1", "--out", "none",
                      cwd=tmp_path)
    assert done.returncode == 1 and "no joint controllers" in done.stderr
    assert "Traceback" not in done.stderr and not (tmp_path / "none").exists()
