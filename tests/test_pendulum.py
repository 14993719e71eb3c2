"""A simple pendulum against its closed form, in spatial, planar and particle form."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod as hx

from mechanisms import PENDULUM, pendulum, pendulum_closed_form

FORMS = ["spatial", "planar", "particle-3d", "particle-2d"]
STATES = [(0.0, 0.0), (0.7, -1.9), (2.5, 3.1), (-1.2, 0.4)]


def _state(form, theta, theta_dot):
    """Model, consistent q and the velocities of the given angular rate."""
    inertia = 0.0 if form.startswith("particle") else None
    model = hx.assemble(pendulum(form, theta, inertia=inertia))
    data = model.create_data()
    q = hx.assemble_positions(model, data)
    l = PENDULUM["length"]
    v = np.zeros(model.n_v)
    s, c = np.sin(theta), np.cos(theta)
    if form == "spatial":
        # theta about +y: the centre of mass (-l s, 0, -l c) moves with omega = theta_dot e_y
        v[:3] = theta_dot * np.cross([0, 1, 0], [-l * s, 0, -l * c])
        v[3:6] = [0.0, theta_dot, 0.0]  # body axes: the rotation is about body y too
    elif form == "planar":
        v[:] = [l * c * theta_dot, l * s * theta_dot, theta_dot]
    elif form == "particle-3d":
        v[:] = [l * c * theta_dot, 0.0, l * s * theta_dot]
    else:
        v[:] = [l * c * theta_dot, l * s * theta_dot]
    return model, q, v, inertia


def _radial_tangential(form, theta):
    s, c = np.sin(theta), np.cos(theta)
    if form in ("spatial",):
        return np.array([-s, 0, -c]), np.array([-c, 0, s])
    if form == "particle-3d":
        return np.array([s, 0, -c]), np.array([c, 0, s])
    return np.array([s, -c]), np.array([c, s])


@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("theta, theta_dot", STATES)
def test_acceleration_and_multipliers_equal_the_closed_form(form, theta, theta_dot):
    model, q, v, inertia = _state(form, theta, theta_dot)
    data = model.create_data()
    v_dot = hx.forward_dynamics(model, data, 0.0, q, v)
    theta_dd, radial, tangential = pendulum_closed_form(theta, theta_dot, inertia=inertia)
    e_r, e_t = _radial_tangential(form, theta)
    l = PENDULUM["length"]
    # centre-of-mass acceleration: l theta_dd e_t - l theta_dot^2 e_r
    a_expected = l * theta_dd * e_t - l * theta_dot**2 * e_r
    dim = e_r.size
    assert np.allclose(v_dot[:dim], a_expected, rtol=0, atol=1e-12 * (1 + abs(theta_dd)))
    force = radial * e_r + tangential * e_t  # of the pivot on the pendulum
    lam = data.lam
    if form.startswith("particle"):
        # the rod's row (d.d - L^2)/(2L) has gradient d/L = e_r: force = -lam e_r, lam = tension
        assert lam.size == 1
        assert lam[0] == pytest.approx(-radial, rel=1e-12, abs=1e-12)
        assert tangential == pytest.approx(0.0, abs=1e-12)
    else:
        # the revolute's point rows are the components of d = P_child - P_parent: force = -lam
        rows = [model.row_index[f"pivot/{c}"] for c in "xyz"[:dim]]
        assert np.allclose(-lam[rows], force, rtol=0, atol=1e-12 * (1 + np.abs(force).max()))
        angular = v_dot[4] if form == "spatial" else v_dot[2]
        assert angular == pytest.approx(theta_dd, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("form", FORMS)
def test_reported_wrench_is_the_pivot_force_in_the_joint_frame(form):
    theta, theta_dot = 0.9, 1.7
    _, q, v, inertia = _state(form, theta, theta_dot)
    # the joint frame is the world frame at the initial pose, fixed to the child: build the
    # scene hanging down (theta = 0) and evaluate it at theta, where the frame has turned
    model = hx.assemble(pendulum(form, 0.0, inertia=inertia))
    data = model.create_data()
    hx.forward_dynamics(model, data, 0.0, q, v)
    world = hx.joint_wrenches(model, data, frame="world")
    local = hx.joint_wrenches(model, data)
    _, radial, tangential = pendulum_closed_form(theta, theta_dot, inertia=inertia)
    e_r, e_t = _radial_tangential(form, theta)
    force = np.zeros(3)
    force[: e_r.size] = radial * e_r + tangential * e_t
    if form == "particle-3d":
        force = radial * e_r + tangential * e_t
    assert np.allclose(world.force[0], force, atol=1e-12 * np.abs(force).max())
    assert np.allclose(world.torque[0], 0.0, atol=1e-12)
    if form == "spatial":
        R = hx.spatial.rotation_about_axis([0, 1, 0], theta)
        assert np.allclose(local.force[0], R.T @ force, atol=1e-12 * np.abs(force).max())
    if form == "planar":
        c, s = np.cos(theta), np.sin(theta)
        R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
        assert np.allclose(local.force[0], R.T @ force, atol=1e-12 * np.abs(force).max())


def test_driven_pendulum_effort():
    """The check of the effort sign: tau = I_O theta_dd + m g l cos(theta), with theta measured from
    the horizontal (+x) about +z, in the plane with gravity -y."""
    m, l, Ic = PENDULUM["mass"], PENDULUM["length"], PENDULUM["inertia"]
    law = hx.scene.Harmonic(offset=0.4, sin=[0.9], cos=[0.3], frequency=0.7)
    scene = hx.Scene("driven", 2)
    scene.add(hx.scene.PlanarBody("arm", m, Ic, position=[l, 0.0]))
    scene.add(hx.scene.Revolute("motor_pin", "ground", "arm", origin=[0.0, 0.0]))
    scene.add(hx.scene.JointDriver("motor", "motor_pin", law))
    model = hx.assemble(scene)
    for t in np.linspace(0.0, 2.0, 9):
        data = model.create_data()
        q = hx.assemble_positions(model, data, t)
        v = hx.solve_velocities(model, data, t, q)
        hx.forward_dynamics(model, data, t, q, v)
        theta, _, theta_dd = (x.item() for x in law.evaluate(t))
        tau = (Ic + m * l**2) * theta_dd + m * 9.81 * l * np.cos(theta)
        wrenches = hx.joint_wrenches(model, data)
        assert wrenches.effort[0] == pytest.approx(tau, rel=1e-11)
        assert hx.driver_efforts(model, data)["motor"] == pytest.approx(tau, rel=1e-11)


@pytest.mark.parametrize("unit", ["dm", "mm", "in"])
def test_length_unit_changes_no_si_result(unit):
    theta, theta_dot = 0.6, -2.2
    results = []
    for u in ("m", unit):
        model = hx.assemble(pendulum("spatial", theta, unit=u))
        data = model.create_data()
        q = hx.assemble_positions(model, data)
        v = np.zeros(model.n_v)
        v[3:6] = [0.0, theta_dot, 0.0]
        v = hx.solve_velocities(model, data, 0.0, q, v)
        v_dot = hx.forward_dynamics(model, data, 0.0, q, v)
        w = hx.joint_wrenches(model, data)
        results.append((q, v, v_dot, w.force, w.torque))
    for a, b in zip(*results, strict=True):
        assert np.allclose(a, b, rtol=1e-12, atol=1e-12)
