"""Whatever the ground-force policy, each foot's status says whether the ground can give it the
force the inverse dynamics asks for (hexapod.algorithms.ground.feet_status), and the outputs
say so.

The case: the walking robot at 1.2 m/s with duty factor 0.75 (a gait no real ground allows:
the summed vertical ground force falls below zero, the robot's trunk is pulled down faster than
gravity would take it). Its statuses are checked against the forces by the physical rule
written out here on its own (normal force below zero; tangential force above mu times the
normal force; beyond 1e-7 of the robot's weight, five orders above round-off), and the
premise itself against the forces: some stance sample must have the ground pulling.
"""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest

import hexapod as hx
from hexapod.algorithms.balance import body_balance
from hexapod.output.ground import foot_loads
from hexapod.output.report import RunInfo, summary_markdown
from legs.robot import hexapod_walking

TIMES = np.linspace(0.0, 0.5, 51)  # one stride at this speed and duty, 10 ms apart


def impossible_gait(policy: str):
    scene = hexapod_walking(speed=1.2, duty=0.75)
    scene.ground = dataclasses.replace(scene.ground, policy=policy)
    model = hx.assemble(scene)
    return model, hx.inverse_dynamics(model, TIMES)


@pytest.fixture(scope="module")
def least_wrench():
    return impossible_gait("min-wrench")


def physical_status(model, result) -> np.ndarray:
    """The rule, from the forces and the contacts' schedules alone."""
    weight = model.total_mass * float(np.linalg.norm(model.gravity))
    tolerance = 1e-7 * weight
    force = result.ground_force
    normal, tangential = force[..., 2], np.hypot(force[..., 0], force[..., 1])
    stance = np.array([[bool(c.in_stance(t)) for c in model.contacts] for t in TIMES])
    status = np.where(stance, "ok", "swing").astype("<U5")
    status[stance & (tangential > model.ground.mu * np.maximum(normal, 0) + tolerance)] = "slip"
    status[stance & (normal < -tolerance)] = "pull"
    return status


@pytest.mark.parametrize("policy", ["min-wrench", "min-effort", "friction"])
def test_an_impossible_gait_is_flagged_whatever_the_policy(policy, least_wrench):
    model, result = least_wrench if policy == "min-wrench" else impossible_gait(policy)
    weight = model.total_mass * float(np.linalg.norm(model.gravity))
    assert result.ground_force[..., 2].sum(axis=1).min() < -0.1 * weight  # the premise
    assert np.array_equal(result.ground_status, physical_status(model, result))
    assert (result.ground_status == "pull").any()
    assert not result.feasible
    assert np.array_equal(result.infeasible,
                          np.isin(result.ground_status, ("slip", "pull")).any(axis=1))


def test_the_summary_says_infeasible_with_counts_first_time_and_margins(least_wrench):
    model, result = least_wrench
    loads = foot_loads(model, result)
    balance = body_balance(model, result.times, result.q, result.v, result.v_dot,
                           result.force, result.torque, result.frame)
    text = summary_markdown(model, result, balance, RunInfo("hexapod", "hexapod", 1.0, "x"),
                            [], [], loads, None)
    bad = np.isin(result.ground_status, ("slip", "pull"))
    assert (f"**Infeasible**: at {int(bad.any(axis=1).sum())} of {TIMES.size} samples"
            in text)
    table = text.partition("**Infeasible**")[2]
    for c, leg in enumerate(loads.legs):
        row = re.search(rf"^\| {leg} \| (\d+) \| (\d+) \| ([\d.]+) \|", table, re.M)
        if not bad[:, c].any():
            assert row is None
            continue
        assert int(row.group(1)) == np.sum(result.ground_status[:, c] == "slip")
        assert int(row.group(2)) == np.sum(result.ground_status[:, c] == "pull")
        assert float(row.group(3)) == pytest.approx(TIMES[np.argmax(bad[:, c])], abs=1e-4)
