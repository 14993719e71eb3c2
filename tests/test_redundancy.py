"""Redundant constraints: a four-bar built in 3-D with four parallel revolute axes.

Its 3-D model has 3 redundant rows (the loop-closing joint's out-of-plane rows); accelerations stay
unique and equal the planar model's. The multipliers of the redundant rows follow the unit-free
least-wrench policy, so neither the length unit nor the scaling of a row changes a reported force,
while plain minimum-norm multipliers would (checked, so the test can tell them apart).
"""

from __future__ import annotations

import numpy as np
import pytest

import hexapod as hx
from hexapod.algorithms.liaison import joint_wrenches, policy_map, wrenches_from_multipliers
from hexapod.algorithms.linalg import solve_saddle

from mechanisms import four_bar, solve_state

THETA = 1.05
TILTED = [0.0, -9.81 * np.cos(0.35), -9.81 * np.sin(0.35)]  # gravity with an out-of-plane part


def test_four_bar_in_3d_names_three_redundant_rows():
    model, q, _, _, data = solve_state(four_bar(3, THETA), 0.3)
    names = [model.rows[i].name for i in data.redundant_rows]
    assert names == ["rocker_ground/z", "rocker_ground/ax1", "rocker_ground/ax2"]
    mobility = hx.degrees_of_freedom(model, data, 0.3, q)
    assert mobility["dof"] == 1 and mobility["dof_with_drivers"] == 0
    assert mobility["redundant_rows"] == names
    planar = hx.assemble(four_bar(2, THETA))
    planar_data = planar.create_data()
    q2 = hx.assemble_positions(planar, planar_data, 0.3)
    assert hx.degrees_of_freedom(planar, planar_data, 0.3, q2) == {
        "dof": 1, "dof_with_drivers": 0, "redundant_rows": []}


def _planar_view(model3, v3):
    """Map spatial velocities (vx, vy, vz, wx_body, wy_body, wz_body) of z-axis rotations to
    (vx, vy, w)."""
    out = []
    for b in model3.bodies:
        x = v3[b.v]
        out += [x[0], x[1], x[5]]
    return np.array(out)


@pytest.mark.parametrize("driven", [True, False])
def test_accelerations_equal_the_planar_model(driven):
    scene3 = four_bar(3, THETA, driven=driven, gravity=[0, -9.81, 0])
    scene2 = four_bar(2, THETA, driven=driven)
    model2 = hx.assemble(scene2)
    model3 = hx.assemble(scene3)
    t = 0.3
    data2, data3 = model2.create_data(), model3.create_data()
    q2 = hx.assemble_positions(model2, data2, t)
    q3 = hx.assemble_positions(model3, data3, t)
    if driven:
        v2 = hx.solve_velocities(model2, data2, t, q2)
        v3 = hx.solve_velocities(model3, data3, t, q3)
    else:  # the same state in both: a crank rate of 3 rad/s carried through the loop
        v2 = hx.solve_velocities(model2, data2, t, q2, np.array([0, 0, 3.0] + [0.0] * 6))
        v3 = np.zeros(model3.n_v)
        for b, b2 in zip(model3.bodies, model2.bodies, strict=True):
            v3[b.v.start:b.v.start + 2] = v2[b2.v][:2]
            v3[b.v.start + 5] = v2[b2.v][2]
    assert np.allclose(_planar_view(model3, v3), v2, atol=1e-12)
    data2, data3 = model2.create_data(), model3.create_data()
    a2 = hx.forward_dynamics(model2, data2, t, q2, v2)
    a3 = hx.forward_dynamics(model3, data3, t, q3, v3)
    assert data3.redundant_rows.size == 3 and data2.redundant_rows.size == 0
    assert np.allclose(_planar_view(model3, a3), a2, rtol=1e-10, atol=1e-10 * np.abs(a2).max())
    # nothing leaves the plane
    assert np.abs([a3[b.v][2:5] for b in model3.bodies]).max() < 1e-10 * np.abs(a2).max()
    # in-plane wrenches are determinate and equal the planar model's; with in-plane loads the
    # policy puts nothing out of the plane
    w2 = joint_wrenches(model2, data2, frame="world")
    w3 = joint_wrenches(model3, data3, frame="world")
    size = np.abs(w2.force).max()
    assert np.allclose(w3.force[:, :2], w2.force[:, :2], atol=1e-10 * size)
    assert np.allclose(w3.torque[:, 2], w2.torque[:, 2], atol=1e-10 * size)
    assert np.abs(w3.force[:, 2]).max() < 1e-10 * size
    assert np.abs(w3.torque[:, :2]).max() < 1e-10 * size
    if driven:
        assert w3.effort[0] == pytest.approx(w2.effort[0], rel=1e-10)


def _wrenches(scene, t=0.3):
    model, q, _, _, data = solve_state(scene, t)
    return model, q, data, joint_wrenches(model, data, frame="world")


def test_length_unit_changes_no_reported_force():
    _, _, data_m, metres = _wrenches(four_bar(3, THETA, gravity=TILTED))
    _, _, data_dm, decimetres = _wrenches(four_bar(3, THETA, gravity=TILTED, unit="dm"))
    assert data_m.redundant_rows.size == data_dm.redundant_rows.size == 3
    size = np.abs(metres.force).max()
    assert np.abs(metres.force[:, 2]).max() > 0.1 * size  # out-of-plane forces are at stake
    assert np.allclose(decimetres.force, metres.force, rtol=0, atol=1e-10 * size)
    assert np.allclose(decimetres.torque, metres.torque, rtol=0, atol=1e-10 * size)


def test_scaling_a_row_changes_no_reported_force():
    model, q, data, reference = _wrenches(four_bar(3, THETA, gravity=TILTED))
    for row in ("rocker_ground/z", "coupler_pin/ax1", "crank_pin/x"):
        k = model.row_index[row]
        scale = np.ones(model.n_c)
        scale[k] = 37.0
        Phi_v = data.Phi_v * scale[:, None]
        gamma = data.gamma * scale
        wrench_map, offset = policy_map(model, q, data.w, Phi_v)
        solution = solve_saddle(model.mass_inv_sqrt, Phi_v, data.Q, gamma, model.row_priority,
                                model.rank_tolerance, wrench_map=wrench_map,
                                wrench_offset=offset)
        scaled = wrenches_from_multipliers(model, q, solution.lam, Phi_v, frame="world")
        size = np.abs(reference.force).max()
        assert np.allclose(scaled.force, reference.force, rtol=0, atol=1e-10 * size)
        assert np.allclose(scaled.torque, reference.torque, rtol=0, atol=1e-10 * size)
        assert np.allclose(solution.v_dot, data.v_dot, rtol=1e-12, atol=1e-12)


def _minimum_norm_wrenches(model, q, data, row_scale):
    """What plain minimum-norm multipliers would report (not acceptable: they change with the length
    unit)."""
    Phi_v = data.Phi_v * row_scale[:, None]
    rhs = data.Q - model.mass @ data.v_dot
    lam = np.linalg.lstsq(Phi_v.T, rhs, rcond=None)[0]
    return wrenches_from_multipliers(model, q, lam, Phi_v, frame="world")


def test_plain_minimum_norm_multipliers_would_fail_these_tests():
    """The invariance tests above can fail: minimum-norm multipliers change with a row scale."""
    model, q, data, reference = _wrenches(four_bar(3, THETA, gravity=TILTED))
    plain = _minimum_norm_wrenches(model, q, data, np.ones(model.n_c))
    scale = np.ones(model.n_c)
    scale[model.row_index["rocker_ground/z"]] = 37.0
    scaled = _minimum_norm_wrenches(model, q, data, scale)
    size = np.abs(reference.force).max()
    assert np.abs(scaled.force - plain.force).max() > 1e-3 * size


def test_contradicting_drivers_are_named():
    """A second driver whose law matches the pose at t = 0 but prescribes a speed the crank's
    law cannot produce: the velocity analysis names it instead of ignoring it."""
    scene = four_bar(2, THETA)
    scene.add(hx.scene.JointDriver("second", "rocker_ground", hx.scene.Polynomial([0.0, 5.0])))
    model = hx.assemble(scene)
    data = model.create_data()
    q = hx.assemble_positions(model, data, 0.0)
    with pytest.raises(hx.SingularSystemError, match="second"):
        hx.solve_velocities(model, data, 0.0, q)
