"""The walking robot on real ground (``legs.replay.grounded_scene``): each joint under a PD
controller fed forward with the inverse dynamics' efforts, each foot a unilateral contact with
Coulomb friction, simulated by Moreau-Jean. The study of many strides is
``scripts/studies/walking_on_ground.py``; here the first 20 ms of a stride, where the forward
run and the inverse dynamics must agree: the feet the gait keeps down are pushed by the
ground, those it lifts are not, and each stance foot's normal force is the inverse dynamics'
to 1 N (0.5 % of the weight: the joints track to 0.1 mrad, measured 0.07 with the step's
forces and Jacobians at mid-step, 0.14 at its start; the forces measured within 0.24 N). With
the robot's actuator table each controller is limited by its motor.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from robots import builtin_model

import hexapod as hx
from hexapod.output.ground import ground_columns
from legs.replay import grounded_scene
from legs.robot import hexapod_scene

ROOT = Path(__file__).resolve().parents[1]
WINDOW = 0.05  # s: the efforts tabulated (one spline piece)
RUN = 0.02  # s simulated


@pytest.fixture(scope="module")
def on_ground():
    scene = hexapod_scene(gait="tripod", trunk="free", period=0.5)
    driven = builtin_model("hexapod")  # the same robot, assembled once per test process
    times = np.linspace(0.0, WINDOW, 26)
    inverse = hx.inverse_dynamics(driven, times)
    table = hx.scene.read_actuators(ROOT / "data" / "actuators" / "hexapod.toml")
    grounded = grounded_scene(scene, inverse, kp=200.0, kd=2.0, breaks=[0.0, WINDOW],
                              actuators=table)
    model = hx.assemble(grounded)
    run = hx.simulate(model, RUN, method="moreau-jean", step=1e-3)
    return driven, inverse, grounded, table, run


def test_the_laws_read_ahead_give_the_run_of_laws_read_one_time_at_a_time(on_ground,
                                                                          monkeypatch):
    """Moreau-Jean evaluates its fixed steps' laws in batches ahead of them: the run is the
    same, bit for bit, as one that evaluates them at each step."""
    from hexapod.simulation.integrators.moreau_jean import MoreauJean

    *_, grounded, _, run = on_ground
    monkeypatch.setattr(MoreauJean, "_laws_ahead", lambda self: None)
    alone = hx.simulate(hx.assemble(grounded), RUN, method="moreau-jean", step=1e-3)
    assert np.array_equal(alone.q, run.q) and np.array_equal(alone.v, run.v)
    assert np.array_equal(alone.contact_forces, run.contact_forces)


def test_a_projected_states_residuals_are_those_the_model_measures_there(on_ground):
    """The projection's residuals serve the run's watch in place of three more calls: they
    are the model's own ``phi`` and ``Phi_v v - nu`` at the state it returned, scaled, and
    are not given for another state."""
    *_, grounded, _, _ = on_ground
    model = hx.assemble(grounded)
    integrator = hx.simulation.get_integrator("moreau-jean")(model, 0.0, RUN, step=1e-3)
    for _ in range(3):
        integrator.step()
    phi, rate = integrator.state_residuals()
    t, q, v = integrator.t, integrator.q, integrator.v
    w, wd, _ = model.law_values(t)
    scale = model.row_scale
    expected_phi = np.abs(model.call("phi", q=q, w=w) / scale).max()
    expected_rate = np.abs((model.call("Phi_v", q=q, w=w) @ v
                            - model.call("nu", q=q, w=w, wd=wd)) / scale).max()
    # round-off: measured 5e-16 and 1e-12 (222 velocities, the projection's conditioning)
    assert 0.0 < phi < 1e-11 and 0.0 < rate < 1e-11
    assert abs(phi - expected_phi) <= 1e-14 and abs(rate - expected_rate) <= 1e-13
    integrator.v = v.copy()
    assert integrator.state_residuals() is None


def test_the_controllers_take_their_motors_limits(on_ground):
    _, _, grounded, table, _ = on_ground
    servos = [f for f in grounded.forces.values() if isinstance(f, hx.scene.JointController)]
    assert len(servos) == 36
    motors = table.assign([s.joint for s in servos])
    for servo in servos:
        motor = motors[servo.joint]
        assert servo.max_effort == pytest.approx(motor.gear_ratio * motor.stall_torque)
        assert servo.no_load_speed == pytest.approx(motor.no_load_speed / motor.gear_ratio)


def test_the_first_steps_on_the_ground_carry_the_inverse_dynamics_forces(on_ground):
    driven, inverse, _, _, run = on_ground
    assert run.status == "finished"
    assert np.abs(run.tracking).max() < 1e-4
    k = int(np.argmin(np.abs(run.t - RUN)))
    j = int(np.argmin(np.abs(inverse.times - RUN)))
    assert run.t[k] == pytest.approx(RUN) and inverse.times[j] == pytest.approx(RUN)
    simulated, expected = run.contact_forces[k], inverse.ground_force[j]
    stance = np.array([bool(c.in_stance(RUN)) for c in driven.contacts])
    assert stance.sum() == 3
    assert np.all(simulated[stance, 2] > 10.0) and np.all(simulated[~stance] == 0.0)
    assert np.abs(simulated[stance, 2] - expected[stance, 2]).max() < 1.0


def test_the_ground_forces_are_named_as_the_inverse_dynamics_names_them(on_ground):
    """``GRx:<leg>`` in both: a designer lays the simulated feet's forces over the inverse
    dynamics' column by column."""
    driven, inverse, _, _, run = on_ground
    simulated = [c for c in run.column_units() if c.startswith("GR")]
    expected = [c for c in ground_columns(driven) if c.startswith("GR")]
    assert simulated == expected and "GRz:L1" in simulated


def test_the_built_in_walking_robot_on_ground_simulates_from_the_command_line(tmp_path):
    """``hexapod simulate hexapod-on-ground``: Moreau-Jean by default, the ground's force on
    each foot under its leg's name, three feet pushed (the tripod in stance), the events and
    the figures a designer reads."""
    import csv
    import json

    from hexapod.cli.app import main

    out = tmp_path / "walk"
    assert main(["simulate", "hexapod-on-ground", "--t-end", "0.01", "--step", "1e-3", "--out",
                 str(out)]) == 0
    assert json.loads((out / "stats.json").read_text())["method"] == "moreau-jean"
    with open(out / "results.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    legs = ("L1", "L2", "L3", "R1", "R2", "R3")
    assert all(f"GRz:{leg}" in rows[0] for leg in legs)
    pushed = [leg for leg in legs if float(rows[-1][f"GRz:{leg}"]) > 10.0]
    assert pushed == ["L2", "R1", "R3"]  # the tripod the gait keeps down at first
    assert all(float(rows[-1][f"GRz:{leg}"]) == 0.0 for leg in legs if leg not in pushed)
    for name in ("events.csv", "contacts.png", "gait.png", "tracking.png"):
        assert (out / name).is_file(), name


def test_the_schedule_is_met_by_first_landings_and_last_leavings_and_grazes_are_named():
    """``schedule_lateness`` matches each scheduled touch-down with the foot's first landing
    around it and each lift-off with its last leaving (a bounce is not hidden by a later
    landing on time); ``grazes`` names the touches without time on the ground, which
    ``event_times(..., with_grazes=False)`` leaves out. Tripod, 0.5 s: L1, R2, L3 land at
    0.2 s; R1, L2, R3 leave at 0.25 s and land at 0.45 s."""
    from types import SimpleNamespace

    from legs.replay import event_times, grazes, schedule_lateness

    def event(t, kind, foot, impulse=(0.0, 0.0, 0.0)):
        return SimpleNamespace(t=t, kind=kind, contact=f"{foot}/ground",
                               impulse=np.array(impulse))

    events = [event(t, "lift-off", foot) for foot, t in
              (("L1", 2e-4), ("R2", 2e-4), ("L3", 2e-4), ("R1", 0.2501), ("L2", 0.2502),
               ("R3", 0.2503))]
    events += [event(0.1985, "touch-down", "L1"), event(0.1985, "impact", "L1", (0, 0, 1e-9)),
               event(0.1985, "lift-off", "L1"), event(0.2002, "touch-down", "L1")]
    events += [event(0.2001, "touch-down", foot) for foot in ("R2", "L3")]
    events += [event(0.447, "touch-down", "R1"), event(0.448, "lift-off", "R1"),
               event(0.4501, "touch-down", "R1")]
    events += [event(0.4504, "touch-down", foot) for foot in ("L2", "R3")]
    events.sort(key=lambda e: e.t)
    model = builtin_model("hexapod")
    assert [(t, name) for t, name, _ in grazes(events)] == [(0.1985, "L1/ground")]
    assert grazes(events)[0][2][2] == 1e-9
    every = schedule_lateness(model, event_times(events), 0.5)
    landed = schedule_lateness(model, event_times(events, with_grazes=False), 0.5)
    assert every["touch-down"] == pytest.approx(3e-3) == landed["touch-down"]  # R1's bounce
    assert every["lift-off"] == pytest.approx(3e-4) == landed["lift-off"]
    events = [e for e in events if e.contact != "R1/ground" or e.t < 0.44]
    events.append(event(0.4501, "touch-down", "R1"))
    assert schedule_lateness(model, event_times(events), 0.5)["touch-down"] == pytest.approx(
        1.5e-3)  # L1's graze
    assert schedule_lateness(model, event_times(events, with_grazes=False), 0.5)[
        "touch-down"] == pytest.approx(4e-4)
    events = [e for e in events if e.contact != "L2/ground" or e.kind != "lift-off"]
    assert schedule_lateness(model, event_times(events), 0.5)["lift-off"] == np.inf


@pytest.mark.slow  # a stride event-driven: some 50 s of CPU
def test_event_driven_the_robot_lands_on_the_schedule():
    """The tripod stride on real ground by the event-driven scheme (gains by the rule at 150
    Hz, the feedforward fitted to 1e-8; ``scripts/studies/walking_on_ground.py --method
    event-driven``): every foot touches the ground within 1 ms of the schedule, the touches
    with no time on the ground before some landings included (measured 0.41 ms over ten
    strides), lands within 0.5 ms and leaves within 0.5 ms (0.30 over ten); the touches'
    impulses are under 1e-9 N s (8.3e-11 at most over ten strides: the feet arrive at zero
    speed); the stance feet's normal forces within 0.1 N of the inverse dynamics' (0.0385)
    away from their ends."""
    from legs.efforts import adaptive_inverse
    from legs.replay import event_times, grazes, schedule_lateness

    scene = hexapod_scene(gait="tripod", trunk="free", period=0.5)
    driven = hx.assemble(scene)
    inverse, _ = adaptive_inverse(driven, scene, 0.0, 0.5, tol=1e-8)
    kp, kd = hx.simulation.critical_gains(driven, inverse.q[0], 150.0)
    model = hx.assemble(grounded_scene(scene, inverse, kp=kp, kd=kd, mu=0.8, periodic=True))
    run = hx.simulate(model, 0.5, method="event-driven", rtol=1e-6)
    assert run.success, run.message
    landed = schedule_lateness(driven, event_times(run.events, with_grazes=False), 0.5)
    assert landed["touch-down"] < 5e-4 and landed["lift-off"] < 5e-4
    assert schedule_lateness(driven, event_times(run.events), 0.5)["touch-down"] < 1e-3
    assert all(np.linalg.norm(p) < 1e-9 for *_, p in grazes(run.events))
    names = [c.name for c in driven.contacts]
    order = [run.contact_names.index(n) for n in names]
    for c, contact in enumerate(driven.contacts):
        wanted = np.interp(run.t, inverse.times, inverse.ground_force[:, c, 2])
        for a, b in contact.stances(0.0, 0.5):
            inside = (run.t > a + 0.02) & (run.t < b - 0.02)
            assert np.abs(run.contact_forces[inside, order[c], 2] - wanted[inside]).max() < 0.1
