"""Free-body balance of the reported liaison wrenches, and actuator efforts.

For every body the joint wrenches of the report (the report convention: exerted by the parent on the
child, about the joint origin, in the child's joint frame) must, once taken back to world axes and
to the body's centre of mass, balance its motion with gravity and the loads that do not act across a
joint:

    sum_{joints, body is child} W_k  -  sum_{joints, body is parent} W_k  +  loads
        = (m a_G,  J omega_dot + omega x J omega)

The joint frames and origins used to undo the report are computed here from the scene (the
joint frame drawn at the initial pose, carried along by the child's motion), not taken from
the engine, so a wrong rotation or a wrong moment point in the report cannot cancel out. Spring
dampers and actuator efforts acting across a joint belong to that joint's wrench (they are not
added again); the other loads are written here from their definitions.

Efforts: a driven revolute joint reports ``effort = -lambda`` of its driver
(``hexapod.driver_efforts``) plus the actuator efforts on it, and for a driven pendulum that is
``I_O theta_dd + m g l cos(theta)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import hexapod as hx
from legs.front_leg import front_leg_scene

G = 9.81  # m/s^2
RNG_SEED = 20261124

# The balance is M v_dot + Phi_v^T lambda = Q read body by body after the report's rotations and
# moment transfers: round-off, plus the assembly tolerance (positions meet the joints to ~1e-13
# m, which moves the reaction's moment point on the parent by as much), gives <= 1e-12 relative
# to the largest term of the body; 1e-9 leaves three orders of margin, while a wrong frame, sign
# or moment point gives errors of order one.
BALANCE_RTOL = 1e-9
# Efforts against closed forms built from the same state: round-off only.
EFFORT_RTOL = 1e-10


def rotation_from_parameters(p):
    """Rotation of scalar-first Euler parameters (SciPy stores the scalar last)."""
    return Rotation.from_quat([p[1], p[2], p[3], p[0]]).as_matrix()


def rot_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def embed(x):
    """A planar vector (2,) as a spatial one (3,), z = 0; spatial vectors pass through."""
    x = np.asarray(x, dtype=float)
    return x if x.size == 3 else np.array([x[0], x[1], 0.0])


def embed_rotation(R):
    R = np.asarray(R, dtype=float)
    if R.shape == (3, 3):
        return R
    out = np.eye(3)
    out[:2, :2] = R
    return out


def body_pose(model, q, index):
    """Centre of mass and rotation (3-D; planar bodies turn about z), read from ``q``."""
    info = model.bodies[index]
    qb = q[info.q]
    if info.kind == "planar":
        return embed(qb[:2]), rot_z(qb[2])
    return qb[:3], rotation_from_parameters(qb[3:])


def body_motion(model, vb, kind):
    """Velocity of the centre of mass and angular velocity in body axes, as 3-vectors."""
    if kind == "planar":
        return embed(vb[:2]), np.array([0.0, 0.0, vb[2]])
    return vb[:3], vb[3:]


# ------------------------------------------------------------------ what the test knows itself


@dataclass
class Loads:
    """Loads that act on single bodies (not across a joint), as the test computes them."""

    forces: list = field(default_factory=list)  # (scene force element) AppliedForce
    torques: list = field(default_factory=list)  # AppliedTorque
    springs: list = field(default_factory=list)  # SpringDamper not across a joint


class Reference:
    """Independent readings of a scene (spatial or planar, embedded in 3-D) at a state: joint
    frames from the drawing of the scene, body points from the scene's reference frames, load
    forces from their definitions."""

    def __init__(self, scene: hx.Scene, model: hx.Model, q: np.ndarray, v: np.ndarray):
        self.scene, self.model, self.q, self.v = scene, model, q, v
        self.bodies = scene.bodies

    def index(self, name):
        return self.model.body_index[name]

    def pose(self, name):
        """Centre of mass, rotation (reference axes -> world) of a body; the ground is fixed."""
        if name == hx.scene.GROUND:
            return np.zeros(3), np.eye(3)
        return body_pose(self.model, self.q, self.index(name))

    def motion(self, name):
        """Velocity of the centre of mass and angular velocity, world axes."""
        info = self.model.bodies[self.index(name)]
        velocity, omega = body_motion(self.model, self.v[info.v], info.kind)
        return velocity, self.pose(name)[1] @ omega

    def initial_pose(self, name):
        body = self.bodies[name]
        R = embed_rotation(body.rotation)
        return embed(body.position) + R @ embed(body.com), R

    def point(self, name, ref):
        """World position of a point given in a body's reference frame (world on the ground;
        None: the centre of mass)."""
        if name == hx.scene.GROUND:
            return embed(ref)
        r, R = self.pose(name)
        body = self.bodies[name]
        local = body.com if ref is None else np.asarray(ref, dtype=float)
        return r + R @ embed(local - body.com)

    def point_velocity(self, name, world_point):
        if name == hx.scene.GROUND:
            return np.zeros(3)
        velocity, omega = self.motion(name)
        return velocity + np.cross(omega, world_point - self.pose(name)[0])

    def joint_frame(self, joint):
        """Origin and rotation of the joint frame at the state: drawn in world coordinates at
        the initial pose (``origin``, ``rotation``), it moves with the child (stays put when the
        child is the ground)."""
        assert joint.origin is not None
        rotation = np.eye(3) if joint.rotation is None else embed_rotation(joint.rotation)
        if joint.child == hx.scene.GROUND:
            return embed(joint.origin), rotation
        r0, R0 = self.initial_pose(joint.child)
        r, R = self.pose(joint.child)
        return r + R @ R0.T @ (embed(joint.origin) - r0), R @ R0.T @ rotation

    def spring_forces(self, spring):
        """Forces on ``body_a`` and ``body_b`` and their world points: a tension
        ``k (L - L0) + c dL/dt`` pulls the two points together."""
        pa = self.point(spring.body_a, spring.point_a)
        pb = self.point(spring.body_b, spring.point_b)
        d = pb - pa
        length = np.linalg.norm(d)
        u = d / length
        rate = u @ (self.point_velocity(spring.body_b, pb)
                    - self.point_velocity(spring.body_a, pa))
        tension = spring.stiffness * (length - spring.free_length) + spring.damping * rate
        return (tension * u, pa), (-tension * u, pb)

    def inertial_wrench(self, name, v_dot):
        """``m a`` and the rate of angular momentum about the centre of mass, world axes."""
        body = self.bodies[name]
        info = self.model.bodies[self.index(name)]
        _, R = self.pose(name)
        a, omega_dot = body_motion(self.model, v_dot[info.v], info.kind)
        if info.kind == "planar":
            return body.mass * a, R @ (body.inertia * omega_dot)
        J = body.inertia_rotation @ body.inertia @ body.inertia_rotation.T  # body axes
        _, omega = body_motion(self.model, self.v[info.v], info.kind)
        return body.mass * a, R @ (J @ omega_dot + np.cross(omega, J @ omega))


def check_free_body_balance(scene, model, t, q, v, loads: Loads, what=""):
    """Forward dynamics at ``(t, q, v)`` and the balance of every body; returns the data."""
    data = model.create_data()
    v_dot = hx.forward_dynamics(model, data, t, q, v)
    report = hx.joint_wrenches(model, data)
    world = hx.joint_wrenches(model, data, frame="world")
    ref = Reference(scene, model, q, v)
    n_bodies = len(model.bodies)
    # per body: the force terms and the moment terms (about its centre of mass), world axes
    force_terms = [[] for _ in range(n_bodies)]
    moment_terms = [[] for _ in range(n_bodies)]

    def add(name, force, moment_about_point, point, sign=1.0):
        if name == hx.scene.GROUND:
            return
        b = ref.index(name)
        r, _ = ref.pose(name)
        force_terms[b].append(sign * force)
        moment_terms[b].append(sign * (moment_about_point + np.cross(point - r, force)))

    for k, name in enumerate(report.names):
        joint = scene.joints[name]
        origin, R = ref.joint_frame(joint)
        force, moment = R @ report.force[k], R @ report.torque[k]
        # the world-axes report is the same wrench
        scale = max(np.max(np.abs(force)), 1e-300)
        assert np.max(np.abs(world.force[k] - force)) <= BALANCE_RTOL * scale, (
            f"{what}: world-axes force of '{name}' is not the joint-frame one rotated")
        scale = max(np.max(np.abs(moment)), 1e-300)
        assert np.max(np.abs(world.torque[k] - moment)) <= BALANCE_RTOL * scale, (
            f"{what}: world-axes moment of '{name}' is not the joint-frame one rotated")
        add(joint.child, force, moment, origin)  # parent on child
        add(joint.parent, force, moment, origin, sign=-1.0)  # reaction on the parent
    for body_name, body in ref.bodies.items():
        r, _ = ref.pose(body_name)
        add(body_name, body.mass * embed(model.gravity), np.zeros(3), r)
    for element in loads.forces:
        _, R = ref.pose(element.body)
        f = embed([law(t) for law in element.force])
        f = R @ f if element.frame == "body" else f
        add(element.body, f, np.zeros(3), ref.point(element.body, element.point))
    for element in loads.torques:
        r, R = ref.pose(element.body)
        torque = [law(t) for law in element.torque]
        torque = np.array([0.0, 0.0, torque[0]]) if len(torque) == 1 else np.array(torque)
        torque = R @ torque if element.frame == "body" else torque
        add(element.body, np.zeros(3), torque, r)
    for spring in loads.springs:
        (fa, pa), (fb, pb) = ref.spring_forces(spring)
        add(spring.body_a, fa, np.zeros(3), pa)
        add(spring.body_b, fb, np.zeros(3), pb)

    for body_name in ref.bodies:
        b = ref.index(body_name)
        inertial_force, inertial_moment = ref.inertial_wrench(body_name, v_dot)
        forces = np.array(force_terms[b] + [inertial_force])
        moments = np.array(moment_terms[b] + [inertial_moment])
        f_error = np.max(np.abs(np.sum(force_terms[b], axis=0) - inertial_force))
        m_error = np.max(np.abs(np.sum(moment_terms[b], axis=0) - inertial_moment))
        f_scale = np.max(np.abs(forces))
        m_scale = np.max(np.abs(moments))
        assert f_error <= BALANCE_RTOL * f_scale, (
            f"{what}: force balance of '{body_name}' off by {f_error:.3e} (scale {f_scale:.3e})")
        assert m_error <= BALANCE_RTOL * m_scale, (
            f"{what}: moment balance of '{body_name}' off by {m_error:.3e} "
            f"(scale {m_scale:.3e})")
    return data, report


# ------------------------------------------------------------------ the front leg


@pytest.fixture(scope="module")
def front_leg():
    scene = front_leg_scene()
    return scene, hx.assemble(scene)


FRONT_LEG_TIMES = (0.0, 0.083, 0.2, 0.371)


def _front_leg_state(model, t):
    data = model.create_data()
    q = hx.assemble_positions(model, data, t)
    return q, hx.solve_velocities(model, data, t, q)


@pytest.mark.parametrize("t", FRONT_LEG_TIMES)
def test_front_leg_free_body_balance(front_leg, t):
    scene, model = front_leg
    q, v = _front_leg_state(model, t)
    data, _ = check_free_body_balance(scene, model, t, q, v, Loads(), f"front leg, t={t}")
    # the motion is prescribed: the velocities are not trivial (a sanity check of the setup)
    assert np.max(np.abs(v)) > 1e-2


@pytest.mark.parametrize("t", FRONT_LEG_TIMES)
def test_front_leg_efforts_are_minus_driver_multipliers(front_leg, t):
    scene, model = front_leg
    q, v = _front_leg_state(model, t)
    data = model.create_data()
    hx.forward_dynamics(model, data, t, q, v)
    report = hx.joint_wrenches(model, data)
    efforts = hx.driver_efforts(model, data)
    assert len(model.drivers) == len(model.joints) == 6
    scale = np.max(np.abs(report.effort))
    assert scale > 1e-3  # N m: the gait loads the joints
    for driver in model.drivers:
        joint = model.joints[driver.joint]
        assert driver.name == f"drive_{joint.name}"
        assert efforts[driver.name] == -data.lam[driver.row]
        # exact identity up to the report's frame rotation and moment transfer
        assert abs(report.effort[joint.index] - efforts[driver.name]) <= EFFORT_RTOL * scale
        # the effort is the axial component of the reported moment (joint axis: z)
        assert abs(report.torque[joint.index][2] - report.effort[joint.index]) <= (
            EFFORT_RTOL * scale)


# ------------------------------------------------------------------ a random loaded chain


def _random_rotation(rng):
    return Rotation.random(random_state=rng).as_matrix()


def random_loaded_chain(rng, n=4, reversed_root=False):
    """A spatial chain of ``n`` bodies drawn at random poses, revolute joints drawn in world
    coordinates (random origin, frame and axis), full inertia tensors; spring-dampers across
    joints and between bodies that share no joint; applied forces, a torque, a motor. With
    ``reversed_root`` the first joint is written body -> ground (the ground is its child)."""
    scene = hx.Scene("loaded-chain", dimension=3, gravity=[0.5, -1.0, -G])
    previous = np.zeros(3)
    for k in range(n):
        position = previous + rng.uniform(-0.2, 0.2, 3) + [0.4, 0.0, 0.0]
        a, b, c = rng.uniform(0.05, 0.3, 3)
        mass = rng.uniform(0.3, 2.0)
        R = _random_rotation(rng)
        inertia = R @ np.diag(mass / 5 * np.array([b * b + c * c, a * a + c * c,
                                                   a * a + b * b])) @ R.T
        scene.add(hx.scene.SpatialBody(f"b{k}", mass, inertia, com=rng.uniform(-0.2, 0.2, 3),
                                       position=position, rotation=_random_rotation(rng),
                                       inertia_rotation=_random_rotation(rng)))
        parent, child = (hx.scene.GROUND if k == 0 else f"b{k - 1}"), f"b{k}"
        if k == 0 and reversed_root:
            parent, child = child, parent
        scene.add(hx.scene.Revolute(f"j{k}", parent, child,
                                    origin=previous + rng.uniform(-0.1, 0.1, 3),
                                    rotation=_random_rotation(rng), axis=rng.normal(size=3)))
        previous = position
    springs = [
        # across joint j1 (written child first), across j0 (ground end in world coordinates)
        hx.scene.SpringDamper("across_j1", "b1", "b0", point_a=[0.1, 0.05, -0.1],
                              point_b=[-0.05, 0.2, 0.0], stiffness=40.0, damping=3.0,
                              free_length=0.2),
        hx.scene.SpringDamper("across_j0", hx.scene.GROUND, "b0", point_a=[0.0, 0.3, 0.2],
                              point_b=[0.1, 0.0, 0.0], stiffness=25.0, damping=1.5,
                              free_length=0.25),
        # between bodies that share no joint
        hx.scene.SpringDamper("b0_b2", "b0", "b2", point_a=[0.0, 0.1, 0.1], point_b=None,
                              stiffness=60.0, damping=2.0, free_length=0.5),
        hx.scene.SpringDamper("ground_b3", hx.scene.GROUND, "b3", point_a=[1.0, 1.0, 0.5],
                              point_b=[0.05, -0.1, 0.1], stiffness=30.0, damping=4.0,
                              free_length=0.8),
    ]
    forces = [
        hx.scene.AppliedForce("push_b1", "b1", [3.0, -2.0, 5.0], point=[0.2, -0.1, 0.05]),
        hx.scene.AppliedForce("push_b3", "b3", [-1.5, 4.0, 2.5], point=[-0.1, 0.15, 0.3],
                              frame="body"),
        hx.scene.AppliedForce("pull_b2", "b2", [0.0, 0.0, 6.0]),  # at the centre of mass
    ]
    torques = [hx.scene.AppliedTorque("twist_b2", "b2", [0.3, -0.4, 0.8], frame="body")]
    motor = hx.scene.JointEffort("motor_j2", "j2", 1.7)  # across j2: part of its wrench
    scene.add(*springs, *forces, *torques, motor)
    loads = Loads(forces=forces, torques=torques, springs=springs[2:])
    return scene, loads


@pytest.mark.parametrize(("seed", "reversed_root"), [(0, False), (1, False), (2, True)])
def test_loaded_chain_free_body_balance(seed, reversed_root):
    rng = np.random.default_rng(RNG_SEED + seed)
    scene, loads = random_loaded_chain(rng, reversed_root=reversed_root)
    model = hx.assemble(scene)
    assert [j.across for j in model.joints] == [("across_j0",), ("across_j1",), ("motor_j2",),
                                                ()]
    for trial in range(2):
        guess = model.integrate(model.q0, rng.normal(scale=0.4, size=model.n_v))
        data = model.create_data()
        q = hx.assemble_positions(model, data, q=guess)
        v = hx.solve_velocities(model, data, 0.0, q, rng.normal(scale=1.5, size=model.n_v))
        check_free_body_balance(scene, model, 0.0, q, v, loads, f"seed {seed}, state {trial}")


def random_planar_chain(rng, n=3):
    """The planar counterpart: planar bodies at random poses, revolute joints at random points
    with random joint frames, the same kinds of loads (report embedded in 3-D)."""
    scene = hx.Scene("planar-chain", dimension=2, gravity=[0.8, -G])
    previous = np.zeros(2)
    for k in range(n):
        position = previous + rng.uniform(-0.1, 0.1, 2) + [0.5, 0.0]
        scene.add(hx.scene.PlanarBody(f"b{k}", rng.uniform(0.3, 2.0), rng.uniform(0.01, 0.1),
                                      com=rng.uniform(-0.2, 0.2, 2), position=position,
                                      angle=rng.uniform(-np.pi, np.pi)))
        angle = rng.uniform(-np.pi, np.pi)
        scene.add(hx.scene.Revolute(f"j{k}", hx.scene.GROUND if k == 0 else f"b{k - 1}", f"b{k}",
                                    origin=previous + rng.uniform(-0.1, 0.1, 2),
                                    rotation=[[np.cos(angle), -np.sin(angle)],
                                              [np.sin(angle), np.cos(angle)]]))
        previous = position
    springs = [
        hx.scene.SpringDamper("across_j1", "b1", "b0", point_a=[0.1, 0.1], point_b=[0.2, -0.1],
                              stiffness=30.0, damping=2.0, free_length=0.1),
        hx.scene.SpringDamper("ground_b2", hx.scene.GROUND, "b2", point_a=[1.5, 1.0],
                              point_b=[0.0, 0.1], stiffness=20.0, damping=1.0, free_length=0.5),
    ]
    forces = [hx.scene.AppliedForce("push_b1", "b1", [2.0, -3.0], point=[0.3, 0.1], frame="body"),
              hx.scene.AppliedForce("push_b0", "b0", [-1.0, 2.5], point=[-0.1, 0.2])]
    torques = [hx.scene.AppliedTorque("twist_b2", "b2", [0.4])]
    motor = hx.scene.JointEffort("motor_j2", "j2", 0.9)
    scene.add(*springs, *forces, *torques, motor)
    return scene, Loads(forces=forces, torques=torques, springs=springs[1:])


@pytest.mark.parametrize("seed", [0, 1])
def test_planar_chain_free_body_balance(seed):
    rng = np.random.default_rng(RNG_SEED + 10 + seed)
    scene, loads = random_planar_chain(rng)
    model = hx.assemble(scene)
    assert [j.across for j in model.joints] == [(), ("across_j1",), ("motor_j2",)]
    for trial in range(2):
        guess = model.integrate(model.q0, rng.normal(scale=0.4, size=model.n_v))
        data = model.create_data()
        q = hx.assemble_positions(model, data, q=guess)
        v = hx.solve_velocities(model, data, 0.0, q, rng.normal(scale=1.5, size=model.n_v))
        _, report = check_free_body_balance(scene, model, 0.0, q, v, loads,
                                            f"planar seed {seed}, state {trial}")
        # planar wrenches are embedded in 3-D: no out-of-plane force, no in-plane moment
        assert np.all(report.force[:, 2] == 0.0) and np.all(report.torque[:, :2] == 0.0)
        # the planar effort is the moment about z (the same number, through a rotation about z)
        assert np.allclose(report.effort, report.torque[:, 2], rtol=0, atol=1e-15)


# ------------------------------------------------------------------ a driven pendulum


@pytest.mark.parametrize("motor", [0.0, 0.7])
def test_driven_pendulum_effort_closed_form(motor):
    """A rod hinged at the origin about z, gravity -y, its angle from the x axis prescribed:
    ``tau = I_O theta_dd + m g l cos(theta)``; with an extra actuator effort ``e`` on the joint
    the driver supplies ``tau - e`` and the report still gives the total ``tau``."""
    m, l, J_zz = 1.7, 0.45, 0.03
    offset, a, b, f = 0.3, 0.5, -0.4, 0.8  # theta = offset + a cos(w t) + b sin(w t)
    w = 2 * np.pi * f
    scene = hx.Scene("driven-pendulum", dimension=3, gravity=[0.0, -G, 0.0])
    scene.add(hx.scene.SpatialBody("rod", m, [0.004, J_zz, J_zz], com=[l, 0.0, 0.0]),
              hx.scene.Revolute("pivot", hx.scene.GROUND, "rod", origin=[0.0, 0.0, 0.0]),
              hx.scene.JointDriver("drive", "pivot",
                                   hx.scene.Harmonic(offset, [a], [b], frequency=f)))
    if motor:
        scene.add(hx.scene.JointEffort("motor", "pivot", motor))
    model = hx.assemble(scene)
    for t in (0.0, 0.21, 0.55, 0.9):
        theta = offset + a * np.cos(w * t) + b * np.sin(w * t)
        theta_dd = -w**2 * (a * np.cos(w * t) + b * np.sin(w * t))
        tau = (J_zz + m * l**2) * theta_dd + m * G * l * np.cos(theta)
        data = model.create_data()
        q, v = hx.consistent_state(model, data, t)
        r, _ = body_pose(model, q, 0)
        # the engine's joint angle is the law's (assembly converges to ~1e-12 m; setup check)
        assert np.allclose(r, l * np.array([np.cos(theta), np.sin(theta), 0.0]), atol=1e-10)
        data, report = check_free_body_balance(scene, model, t, q, v, Loads(),
                                               f"driven pendulum, t={t}")
        driver = model.drivers[0]
        lam_d = data.lam[driver.row]
        scale = m * G * l + abs(tau)
        assert hx.driver_efforts(model, data)["drive"] == -lam_d
        assert abs(report.effort[0] - tau) <= EFFORT_RTOL * scale
        assert abs(-lam_d + motor - tau) <= EFFORT_RTOL * scale


def test_a_joint_torque_cancelled_by_its_forces_moment_is_not_called_unbalanced():
    """An arm turned steadily about a principal axis: on it the hinge's torque and the moment
    of the hinge's force about the centre of mass cancel at every sample, so their sum, the
    body's whole moment term, is round-off. The balance is measured against the parts (each
    up to m g l), not against that sum: round-off relative (it read 1.0 before)."""
    scene = hx.Scene("turning-arm", 3, gravity=[0.0, -G, 0.0])
    scene.add(hx.scene.SpatialBody("arm", 2.0, [0.02] * 3, position=[0.5, 0.0, 0.0]))
    scene.add(hx.scene.Revolute("hinge", "ground", "arm", origin=[0.0, 0.0, 0.0],
                                axis=[0, 0, 1]))
    scene.add(hx.scene.JointDriver("drive", "hinge", hx.scene.Polynomial((0.0, 2 * np.pi))))
    model = hx.assemble(scene)
    t = np.linspace(0.0, 1.0, 101)
    result = hx.inverse_dynamics(model, t)
    balance = hx.body_balance(model, t, result.q, result.v, result.v_dot, result.force,
                              result.torque, result.frame)
    assert balance.moment_scale[0] == pytest.approx(2.0 * G * 0.5, rel=1e-12)
    assert balance.relative().max() < 1e-12
