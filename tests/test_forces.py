"""Force elements and free bodies against Newton-Euler equations written out by hand."""

from __future__ import annotations

import numpy as np
import pytest

import hexapod as hx
from hexapod.spatial import skew

G = np.array([0.0, 0.0, -9.81])


def _fd(model, q, v, t=0.0):
    data = model.create_data()
    return hx.forward_dynamics(model, data, t, q, v), data


def _free_body(rng, **extra):
    J = rng.uniform(0.5, 1.5, 3)
    return hx.scene.SpatialBody("body", 2.0, J, com=[0.1, -0.2, 0.05],
                                position=rng.normal(size=3),
                                rotation=hx.spatial.rotation_about_axis(rng.normal(size=3), 1.1),
                                inertia_rotation=hx.spatial.rotation_about_axis([1, 2, 3], 0.4),
                                velocity=rng.normal(size=3),
                                angular_velocity=rng.normal(size=3) * 2,
                                markers={"tip": hx.spatial.Placement([0.3, 0.1, -0.4])},
                                **extra)


def _euler_rhs(body, R, omega_body, force_world, moment_world):
    """Centre-of-mass acceleration and body angular acceleration of Newton-Euler's equations."""
    J = body.body_inertia
    a = force_world / body.mass + G
    omega_dot = np.linalg.solve(J, R.T @ moment_world - np.cross(omega_body, J @ omega_body))
    return a, omega_dot


def _free_model(seed):
    body = _free_body(np.random.default_rng(seed))
    scene = hx.Scene("free")
    scene.add(body)
    return body, hx.assemble(scene)


def test_free_body_follows_euler_equations():
    """No joint at all: free fall and torque-free rotation of an asymmetric body."""
    body, model = _free_model(1)
    q, v = model.q0, model.v0
    v_dot, data = _fd(model, q, v)
    assert model.n_c == 0 and data.lam.size == 0
    a, omega_dot = _euler_rhs(body, body.rotation, v[3:], np.zeros(3), np.zeros(3))
    assert np.allclose(v_dot[:3], a, atol=1e-13)
    assert np.allclose(v_dot[3:], omega_dot, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("frame", ["world", "body"])
def test_applied_force_and_torque_at_a_marker(frame):
    rng = np.random.default_rng(2)
    body = _free_body(rng)
    f_laws = [hx.scene.Harmonic(offset=1.0, sin=[2.0], frequency=0.5), 3.0,
              hx.scene.Polynomial([0, 1, 1])]
    t_laws = [0.5, hx.scene.Harmonic(cos=[1.5], frequency=1.0), -0.7]
    scene = hx.Scene("loaded")
    scene.add(body)
    scene.add(hx.scene.AppliedForce("push", "body", f_laws, point="tip", frame=frame))
    scene.add(hx.scene.AppliedTorque("twist", "body", t_laws, frame=frame))
    model = hx.assemble(scene)
    t = 0.37
    v_dot, _ = _fd(model, model.q0, model.v0, t)
    R = body.rotation
    F = np.array([hx.scene.laws.as_law(x)(t) for x in f_laws])
    T = np.array([hx.scene.laws.as_law(x)(t) for x in t_laws])
    if frame == "body":
        F, T = R @ F, R @ T
    arm = R @ (body.markers["tip"].position - body.com)  # centre of mass -> marker, world
    a, omega_dot = _euler_rhs(body, R, model.v0[3:], F, T + np.cross(arm, F))
    assert np.allclose(v_dot[:3], a, atol=1e-12)
    assert np.allclose(v_dot[3:], omega_dot, rtol=1e-11, atol=1e-11)


def test_spring_damper_on_a_particle():
    k, c, free = 200.0, 3.0, 0.4
    anchor = np.array([0.1, -0.2, 1.0])
    scene = hx.Scene("spring")
    scene.add(hx.scene.Particle("m", 0.5, position=[0.3, 0.1, 0.2], velocity=[0.4, -1.0, 2.0]))
    scene.add(hx.scene.SpringDamper("s", "ground", "m", point_a=anchor, stiffness=k, damping=c,
                                    free_length=free, force=hx.scene.Constant(1.5)))
    model = hx.assemble(scene)
    v_dot, _ = _fd(model, model.q0, model.v0)
    d = model.q0 - anchor
    length = np.linalg.norm(d)
    e = d / length
    rate = e @ model.v0
    tension = k * (length - free) + c * rate + 1.5
    assert np.allclose(v_dot, -tension * e / 0.5 + G, rtol=1e-12, atol=1e-12)


def test_spring_between_markers_conserves_momentum_balance():
    """Two free bodies joined by a spring between markers: the spring is internal, so the total
    force is the weight and the total moment about the origin is that of the weights."""
    rng = np.random.default_rng(3)
    scene = hx.Scene("pair")
    a = _free_body(rng)
    b = _free_body(rng).replace(name="other")
    scene.add(a, b)
    scene.add(hx.scene.SpringDamper("s", "body", "other", point_a="tip", point_b="tip",
                                    stiffness=150.0, damping=4.0, free_length=0.2))
    model = hx.assemble(scene)
    q, v = model.q0, model.v0
    v_dot, _ = _fd(model, q, v)
    force = np.zeros(3)
    moment = np.zeros(3)
    weight_moment = np.zeros(3)
    for info, body in zip(model.bodies, (a, b), strict=True):
        pose = model.body_pose(q, info.index)
        acc = v_dot[info.v][:3]
        omega, omega_dot = v[info.v][3:], v_dot[info.v][3:]
        J = info.inertia
        force += body.mass * acc
        moment += np.cross(pose.position, body.mass * acc) + pose.rotation @ (
            J @ omega_dot + np.cross(omega, J @ omega))
        weight_moment += np.cross(pose.position, body.mass * G)
    assert np.allclose(force, (a.mass + b.mass) * G, atol=1e-11)
    assert np.allclose(moment, weight_moment, atol=1e-10)


def test_joint_effort_drives_a_pendulum():
    m, l, Ic = 1.2, 0.6, 0.03
    law = hx.scene.Harmonic(offset=2.0, sin=[1.0], frequency=0.8)
    scene = hx.Scene("effort", 2)
    scene.add(hx.scene.PlanarBody("arm", m, Ic, position=[l, 0.0]))
    scene.add(hx.scene.Revolute("hinge", "ground", "arm", origin=[0.0, 0.0]))
    scene.add(hx.scene.JointEffort("motor", "hinge", law))
    model = hx.assemble(scene)
    theta = 0.0
    for t, theta_dot in ((0.2, 0.0), (1.3, 2.5)):
        data = model.create_data()
        v = hx.solve_velocities(model, data, t, model.q0, [-l * np.sin(theta) * theta_dot,
                                                      l * np.cos(theta) * theta_dot, theta_dot])
        v_dot, data = _fd(model, model.q0, v, t)
        tau = law(t)
        assert v_dot[2] == pytest.approx((tau - m * 9.81 * l * np.cos(theta))
                                         / (Ic + m * l**2), rel=1e-12)
        wrenches = hx.joint_wrenches(model, data)
        # the joint wrench gathers the effort acting across the joint
        assert wrenches.effort[0] == pytest.approx(tau, rel=1e-12)
        assert model.joints[0].across == ("motor",)


def test_planar_spring_and_torque():
    scene = hx.Scene("planar", 2)
    scene.add(hx.scene.PlanarBody("plate", 3.0, 0.2, com=[0.05, 0.0], position=[0.2, 0.5],
                                  angle=0.3, velocity=[1.0, -0.5], angular_velocity=2.0,
                                  markers={"corner": [0.2, 0.1]}))
    scene.add(hx.scene.SpringDamper("s", "ground", "plate", point_a=[0.0, 1.0], point_b="corner",
                                    stiffness=80.0, damping=2.0, free_length=0.3))
    scene.add(hx.scene.AppliedTorque("t", "plate", [hx.scene.Constant(0.9)]))
    model = hx.assemble(scene)
    q, v = model.q0, model.v0
    v_dot, _ = _fd(model, q, v)
    R = hx.spatial.rotation_2d(0.3)
    arm = R @ (np.array([0.2, 0.1]) - [0.05, 0.0])
    point = q[:2] + arm
    d = point - [0.0, 1.0]
    length = np.linalg.norm(d)
    e = d / length
    point_velocity = v[:2] + v[2] * np.array([-arm[1], arm[0]])
    tension = 80.0 * (length - 0.3) + 2.0 * (e @ point_velocity)
    force = -tension * e
    assert np.allclose(v_dot[:2], force / 3.0 + [0.0, -9.81], rtol=1e-12)
    moment = arm[0] * force[1] - arm[1] * force[0] + 0.9
    assert v_dot[2] == pytest.approx(moment / 0.2, rel=1e-12)


def test_gyroscopic_term_matches_skew_form():
    """Q's rotational part for a free body is -omega' x J' omega' (body axes), zero without spin."""
    body, model = _free_model(4)
    Q = model.call("Q", q=model.q0, v=model.v0)
    omega = model.v0[3:]
    J = body.body_inertia
    assert np.allclose(Q[3:], -skew(omega) @ J @ omega, rtol=1e-13)
    assert np.allclose(Q[:3], body.mass * G)


def test_scene_without_force_elements_builds_no_force_terms():
    """Leave out what the scene does not need: no springs, no Q_across, no law inputs."""
    scene = hx.Scene("bare", 2)
    scene.add(hx.scene.PlanarBody("b", 1.0, 0.1))
    scene.add(hx.scene.Revolute("r", "ground", "b"))
    model = hx.assemble(scene)
    assert model.Q_across is None and model.n_w == 0 and model.force_names == ()
    assert model.Q.name_in() == ["q", "v"]
    spring = hx.Scene("sprung", 2)
    spring.add(hx.scene.PlanarBody("b", 1.0, 0.1), hx.scene.Revolute("r", "ground", "b"),
               hx.scene.SpringDamper("s", "ground", "b", point_a=[0.0, 1.0], stiffness=1.0))
    assert hx.assemble(spring).Q.n_instructions() > model.Q.n_instructions()


@pytest.mark.parametrize("build", ["planar", "spatial", "cylindrical"])
def test_rotational_spring_damper_on_a_pendulum(build):
    """A torsion spring-damper across the pivot: I_O theta_dd = -k wrap(theta - theta_0)
    - c theta_dot + tau(t) - m g l cos(theta), theta from the horizontal; its torque is part of
    the joint's reported effort (it acts across the joint)."""
    m, l, Ic, k, c, free = 1.1, 0.5, 0.02, 7.0, 0.3, 0.4
    law = hx.scene.Harmonic(offset=0.2, sin=[0.5], frequency=1.5)
    if build == "planar":
        scene = hx.Scene("torsion", 2)
        scene.add(hx.scene.PlanarBody("arm", m, Ic, position=[l, 0.0]))
        scene.add(hx.scene.Revolute("hinge", "ground", "arm", origin=[0.0, 0.0]))
    else:
        scene = hx.Scene("torsion", 3, gravity=[0.0, -9.81, 0.0])
        scene.add(hx.scene.SpatialBody("arm", m, [Ic, Ic, Ic], position=[l, 0.0, 0.0]))
        cls = hx.scene.Revolute if build == "spatial" else hx.scene.joints.Cylindrical
        scene.add(cls("hinge", "ground", "arm", origin=[0.0, 0.0, 0.0], axis=[0, 0, 1]))
        if build == "cylindrical":  # hold the slide so the arm only turns
            scene.add(hx.scene.CoordinateDriver("hold", "arm", "z", 0.0))
    scene.add(hx.scene.forces.RotationalSpringDamper("torsion", "hinge", stiffness=k,
                                                      damping=c, free_angle=free, torque=law))
    model = hx.assemble(scene)
    for t, theta_dot in ((0.0, 0.0), (0.7, -1.8)):
        v = np.zeros(model.n_v)
        v[1] = l * theta_dot
        v[2 if build == "planar" else 5] = theta_dot
        v_dot, data = _fd(model, model.q0, v, t)
        tau = -k * (0.0 - free) - c * theta_dot + law(t)
        theta_dd = (tau - m * 9.81 * l) / (Ic + m * l**2)
        assert v_dot[2 if build == "planar" else 5] == pytest.approx(theta_dd, rel=1e-12)
        wrenches = hx.joint_wrenches(model, data)
        axial = wrenches.torque[0] @ [0, 0, 1]
        assert axial == pytest.approx(tau, rel=1e-12)
