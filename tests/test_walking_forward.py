"""Inverse and forward agree on the walking hexapod (``legs/replay.py``).

The efforts that inverse dynamics finds for the free-trunk hexapod, fed back as actuator efforts
into a forward simulation of the same robot with the same contact schedule, reproduce the
prescribed motion. The twin is unstable (its linearised motion grows as fast as ``exp(210 t)``:
efforts fixed in time do not hold a loaded chain of free joints on its path), so it is replayed
in windows of 10 ms, each from the prescribed state at its start (see the module's description).

**Tolerance and bound.** ``hexapod.simulate`` at its defaults, ``rtol = 1e-6`` and
``atol = 1e-8``: every step's error is held to some ``1e-6`` of the state, whose joint angles
are of order one radian, and over one window the fastest growing mode amplifies what is made
by at most ``exp(210 x 0.01) ~ 8``. Agreement at the level of the tolerance is therefore a
largest joint-angle error of at most ``rtol`` radians, the bound asserted. The effort splines
are accurate to ``3e-6`` of each joint's largest effort (``legs.replay.EFFORT_TOL``), which
moves the angles by a few ``1e-8`` rad over a window (splines to ``1e-5`` left ``3e-7``). Found
(``scripts/studies/walking_forward.py``): ``2.6e-8`` rad over the tripod's stride and ``1.1e-7``
over the wave's. With ``rtol = 1e-8``, ``atol = 1e-10`` the wave's falls to ``1.3e-8`` and the
tripod's stays, the splines' share; both shares converge (the tripod from 0.15 s to 0.18 s:
``5.6e-9`` rad, ``1.0e-11`` with splines to ``1e-8`` and ``rtol = 1e-9``).

**What runs here, what in the script.** The inverse dynamics of a stride takes the most time:
the splines need 317 samples for the tripod and 485 for the wave (their load ramps overlap all
along), some 17 s and 28 s with the replay, too long for the default test run. So the tripod
is checked here from 0.18 s to 0.28 s (a touch-down, a lift-off and both load ramps), the wave
over two windows around one sixth of its stride, where one foot lifts off as another touches
down; ``python3 scripts/studies/walking_forward.py`` checks both whole strides.
"""

import numpy as np
import pytest

import hexapod as hx
from legs.efforts import (
    EffortTable,
    TabulatedEffort,
    effort_breaks,
    lift_off_times,
    switch_times,
)
from legs.replay import replay_gait
from legs.robot import hexapod_scene

#: the run's tolerance, and the bound on the joint-angle error (rad)
RTOL = hx.simulation.DEFAULT_RTOL
PERIOD = 0.5


def test_effort_table_is_exact_at_the_samples_and_smooth_between_them():
    # a function with a jump in its third derivative at the break 0.3
    def f(t):
        return np.sin(10 * t) + 100 * np.abs(t - 0.3) ** 3

    pieces = [np.linspace(0.0, 0.3, 31), np.linspace(0.3, 0.5, 21)[1:]]
    times = np.concatenate(pieces)
    table = EffortTable(times, np.column_stack([f(times), 2 * f(times)]), [0.0, 0.3, 0.5])
    values = table.evaluate(times)
    assert values.shape == (3, times.size, 2)
    assert np.abs(values[0] - np.column_stack([f(times), 2 * f(times)])).max() < 1e-13
    fine = np.linspace(0.0, 0.5, 2001)
    # quintic splines on each side: an error of order (10 h)^6 = 1e-6 times a small constant
    assert np.abs(table.evaluate(fine)[0][:, 0] - f(fine)).max() < 1e-7
    # one spline across the break would miss by far more
    across = EffortTable(times, f(times), [0.0, 0.5])
    assert np.abs(across.evaluate(fine)[0][:, 0] - f(fine)).max() > 1e-6
    # one time at a time (as an integrator asks) gives the same numbers, in any order
    for t in (0.123, 0.3, 0.123, 0.45):
        assert np.allclose(table.evaluate(t), table.evaluate(np.array([t]))[:, 0], rtol=0,
                           atol=1e-15)
    with pytest.raises(ValueError, match="must be sample times"):
        EffortTable(times, f(times), [0.0, 0.305, 0.5])


def test_a_periodic_effort_table_repeats_its_cycle_and_its_breaks():
    """A periodic gait's efforts over one cycle (first and last samples equal) repeat: the
    same values, rates and accelerations a cycle later, and the breaks in every cycle."""
    times = np.concatenate([np.linspace(0.0, 0.3, 31), np.linspace(0.3, 0.5, 21)[1:]])
    values = np.sin(4 * np.pi * times)  # period 0.5
    table = EffortTable(times, values, [0.0, 0.3, 0.5], periodic=True)
    t = np.linspace(0.0, 0.5, 77)[:-1]  # (the cycle's end is the next one's start)
    assert np.allclose(table.evaluate(t + 1.5), table.evaluate(t), rtol=0, atol=1e-9)
    law = TabulatedEffort(table, 0)
    assert law.cycle_time() == 0.5
    assert np.allclose(law.breaks(0.0, 1.2), [0.3, 0.5, 0.8, 1.0])
    assert EffortTable(times, values, [0.0, 0.3, 0.5]).period is None


def test_the_switch_times_follow_the_contact_schedules():
    tripod = hexapod_scene(gait="tripod", trunk="free")
    # duty 0.6: one tripod lifts off at 0 and touches down at 0.4 of the stride, the other half
    # a stride later
    assert np.allclose(switch_times(tripod, 0.0, PERIOD), [0.0, 0.2, 0.25, 0.45, 0.5])
    assert np.allclose(lift_off_times(tripod, 0.0, PERIOD), [0.0, 0.25, 0.5])
    # the load ramps end 0.1 of the stance (0.03 s) after touch-down and before lift-off
    assert np.allclose(effort_breaks(tripod, 0.0, PERIOD),
                       [0.0, 0.2, 0.22, 0.23, 0.25, 0.45, 0.47, 0.48, 0.5])
    wave = hexapod_scene(gait="wave", trunk="free")
    # duty 5/6: every sixth of the stride one foot lifts off as another touches down
    assert np.allclose(switch_times(wave, 0.0, PERIOD), np.arange(7) * PERIOD / 6)
    assert np.allclose(effort_breaks(wave, 0.0, PERIOD), np.arange(13) * PERIOD / 12)


def check(out: dict, t0: float, t1: float) -> None:
    """The twin of :func:`legs.replay.replay_gait`'s output and its agreement from t0 to t1."""
    result, run, agreement = out["result"], out["run"], out["agreement"]
    assert out["sampling"].converged
    assert switch_times(out["scene"], t0, t1).size > 2  # a switch of the schedule inside

    # the twin: the same robot, its 36 joint drivers replaced by efforts (its feet's guides,
    # which exert nothing, left out)
    twin = out["twin"]
    assert not twin.drivers
    efforts = [f for f in twin.forces.values() if isinstance(f, hx.scene.JointEffort)]
    joint_drivers = [d for d in out["scene"].drivers.values() if d.kind == "joint"]
    assert len(efforts) == len(joint_drivers) == 36
    assert twin.joints.keys() == out["scene"].joints.keys()

    # at the samples, the twin's accelerations are the prescribed ones (to round-off over the
    # smallest inertias, the brackets': some 2e-7 rad/s^2 against up to 600)
    model, data = out["twin_model"], out["twin_model"].create_data()
    for k in np.linspace(0, result.times.size - 1, 5).astype(int):
        v_dot = hx.forward_dynamics(model, data, result.times[k], result.q[k], result.v[k])
        assert np.abs(v_dot - result.v_dot[k]).max() < 1e-6 * np.abs(result.v_dot[k]).max()

    # and over the span, window after window, the motion
    assert run.status == "finished", run.message
    assert run.t[0] == pytest.approx(t0, abs=1e-9) and run.t[-1] == pytest.approx(t1, abs=1e-9)
    assert agreement.reference_error < 1e-12  # the angle measure itself
    assert agreement.angle_error < RTOL, (agreement.worst_joint, agreement.worst_time)
    assert agreement.trunk_error < 1e-9  # m, over the last window


def test_the_tripods_efforts_replayed_forward_reproduce_its_stride():
    # from before a touch-down (0.2 s) to after the next lift-off (0.25 s) and the load's ramps
    out = replay_gait("tripod", 0.18, 0.28)
    check(out, 0.18, 0.28)
    assert out["run"].starts.size - 1 == 10  # windows of 10 ms


def test_the_waves_efforts_replayed_forward_reproduce_its_motion_across_a_switch():
    # one sixth of the stride, 0.0833 s: L2 lifts off as L3 touches down
    out = replay_gait("wave", 0.075, 0.095)
    check(out, 0.075, 0.095)
    assert out["run"].starts.size - 1 == 2
