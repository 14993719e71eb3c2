"""Absolute coordinates against minimal coordinates (an independent formulation).

The engine writes every body with its own 7 (or 3, or 2) coordinates and lets the joints remove
the extra freedom through multipliers. Here the same systems are written in joint coordinates,
by hand and with no hexapod code in the reference:

* a planar double pendulum with distributed-mass links: the textbook Lagrange equations
  ``M(theta) theta_dd + C(theta, theta_d) theta_d + g(theta) = 0``, compared with the engine's
  model built from planar bodies, from spatial bodies (joint axes along the body z axes, in the
  world xy plane and in a tilted plane), and, with point masses, from particles and distance
  joints (in the plane and in space);
* random spatial serial chains (2 to 5 bodies, revolute joints about random axes, random
  offsets, centres of mass and full inertia tensors): a recursive Newton-Euler algorithm (RNEA)
  in world components gives the joint forces, its unit-acceleration columns the mass matrix, so
  the joint accelerations of the free chain, the body accelerations, and the force and moment
  each joint transmits from body k-1 to body k about the joint origin. The engine's
  accelerations and its joint wrenches (the report convention) must match, for free
  chains with actuator efforts and for chains whose joints are all driven.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import hexapod as hx
from hexapod.algorithms.liaison import joint_origin
from hexapod.spatial import Placement

G = 9.81  # m/s^2
RNG_SEED = 20261123

# Accelerations of the engine come from one QR solve of a well-conditioned saddle-point system
# built from exact (CasADi) derivatives; the references are closed-form or a few dozen flops
# deep. Observed differences are <= 1e-15 (pendulum) and <= 2e-13 (random chains, including
# the Newton-assembled poses of the driven chains, converged to 1e-12), so 1e-10 and 1e-9 leave
# three orders of margin or more, while any modelling error shows at 1e-3 or above.
PENDULUM_RTOL = 1e-10
CHAIN_RTOL = 1e-9
# Residuals of a configuration built exactly from joint angles: round-off only (~1e-15 m).
CONSISTENCY_ATOL = 1e-12


# ------------------------------------------------------------------ small numpy helpers

def skew(w):
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def rodrigues(axis, angle):
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    K = skew(a)
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * K @ K


def rot_z(angle):
    return rodrigues([0.0, 0.0, 1.0], angle)


def random_rotation(rng):
    return Rotation.random(random_state=rng).as_matrix()


def euler_parameters(R):
    """Scalar-first unit quaternion of a rotation matrix (SciPy stores the scalar last)."""
    x, y, z, w = Rotation.from_matrix(R).as_quat()
    return np.array([w, x, y, z])


def rotation_from_parameters(p):
    return Rotation.from_quat([p[1], p[2], p[3], p[0]]).as_matrix()


def assert_close(actual, expected, rtol, scale=None, what=""):
    """``|actual - expected|_max <= rtol * scale`` (default scale: the largest |expected|)."""
    actual = np.asarray(actual, dtype=float)
    expected = np.asarray(expected, dtype=float)
    assert actual.shape == expected.shape, f"{what}: shape {actual.shape} != {expected.shape}"
    if actual.size == 0:
        return
    if scale is None:
        scale = np.max(np.abs(expected))
    error = np.max(np.abs(actual - expected))
    assert error <= rtol * scale, (
        f"{what}: error {error:.3e} > {rtol:g} x {scale:.3e}\nactual\n{actual}\nexpected\n"
        f"{expected}")


# ================================================================== planar double pendulum


@dataclass(frozen=True)
class Pendulum:
    """Two links hinged at the origin and at the end of link 1 (distance ``l1``); link k has
    mass ``mk``, its centre of mass at ``ck`` along the link and moment of inertia ``Ik`` about
    it. ``l2`` only places the second point mass of the particle model."""

    m1: float
    m2: float
    l1: float
    l2: float
    c1: float
    c2: float
    I1: float
    I2: float


LINKS = Pendulum(m1=1.3, m2=0.7, l1=0.9, l2=0.6, c1=0.42, c2=0.35,
                 I1=1.3 * 0.9**2 / 12 + 0.01, I2=0.7 * 0.6**2 / 12)
POINT_MASSES = Pendulum(m1=1.3, m2=0.7, l1=0.9, l2=0.6, c1=0.9, c2=0.6, I1=0.0, I2=0.0)


def lagrange_accelerations(p: Pendulum, theta, theta_d):
    """Textbook double pendulum (e.g. Spong, Robot Modeling and Control, section 7.4):
    ``theta1`` from the x axis, ``theta2`` of link 2 relative to link 1, gravity -y."""
    t1, t2 = theta
    d1, d2 = theta_d
    M11 = p.I1 + p.I2 + p.m1 * p.c1**2 + p.m2 * (p.l1**2 + p.c2**2
                                                 + 2 * p.l1 * p.c2 * np.cos(t2))
    M12 = p.I2 + p.m2 * (p.c2**2 + p.l1 * p.c2 * np.cos(t2))
    M22 = p.I2 + p.m2 * p.c2**2
    h = p.m2 * p.l1 * p.c2 * np.sin(t2)
    coriolis = np.array([-h * (2 * d1 * d2 + d2**2), h * d1**2])
    gravity = np.array([(p.m1 * p.c1 + p.m2 * p.l1) * G * np.cos(t1)
                        + p.m2 * p.c2 * G * np.cos(t1 + t2),
                        p.m2 * p.c2 * G * np.cos(t1 + t2)])
    M = np.array([[M11, M12], [M12, M22]])
    return np.linalg.solve(M, -(coriolis + gravity))


def _e(phi):
    return np.array([np.cos(phi), np.sin(phi)])


def _n(phi):
    return np.array([-np.sin(phi), np.cos(phi)])


def pendulum_kinematics(p: Pendulum, theta, theta_d, theta_dd=(0.0, 0.0)):
    """Absolute angles, their rates and accelerations, and the centres of mass (plane
    coordinates) with their velocities and accelerations."""
    phi = np.array([theta[0], theta[0] + theta[1]])
    phi_d = np.array([theta_d[0], theta_d[0] + theta_d[1]])
    phi_dd = np.array([theta_dd[0], theta_dd[0] + theta_dd[1]])
    elbow = p.l1 * _e(phi[0])
    elbow_d = p.l1 * phi_d[0] * _n(phi[0])
    elbow_dd = p.l1 * (phi_dd[0] * _n(phi[0]) - phi_d[0] ** 2 * _e(phi[0]))
    r = np.array([p.c1 * _e(phi[0]), elbow + p.c2 * _e(phi[1])])
    r_d = np.array([p.c1 * phi_d[0] * _n(phi[0]), elbow_d + p.c2 * phi_d[1] * _n(phi[1])])
    r_dd = np.array([p.c1 * (phi_dd[0] * _n(phi[0]) - phi_d[0] ** 2 * _e(phi[0])),
                     elbow_dd + p.c2 * (phi_dd[1] * _n(phi[1]) - phi_d[1] ** 2 * _e(phi[1]))])
    return SimpleNamespace(phi=phi, phi_d=phi_d, phi_dd=phi_dd, r=r, r_d=r_d, r_dd=r_dd)


def _in_space(R0, xy):
    return R0 @ np.array([xy[0], xy[1], 0.0])


def _spatial_inertia(I):
    """A full inertia tensor whose moment about the body z axis (the joint axis) is ``I``;
    the other entries do not enter the planar motion (only the constraint moments)."""
    return I * np.array([[0.35, 0.06, 0.09], [0.06, 1.05, -0.07], [0.09, -0.07, 1.0]])


@dataclass
class PendulumCase:
    """One way of building the double pendulum in the engine, and of reading it back."""

    params: Pendulum
    scene: hx.Scene
    state: object  # (kinematics) -> (q, v)
    readout: object  # (v_dot) -> (phi_dd, r_dd (2, 2) plane coordinates, out-of-plane part)


def planar_bodies() -> PendulumCase:
    p = LINKS
    scene = hx.Scene("double-pendulum", dimension=2, gravity=[0.0, -G])
    scene.add(hx.scene.PlanarBody("link1", p.m1, p.I1, com=[p.c1, 0.0]),
              hx.scene.PlanarBody("link2", p.m2, p.I2, com=[p.c2, 0.0], position=[p.l1, 0.0]),
              hx.scene.Revolute("shoulder", hx.scene.GROUND, "link1", origin=[0.0, 0.0]),
              hx.scene.Revolute("elbow", "link1", "link2", origin=[p.l1, 0.0]))

    def state(k):
        q = np.concatenate([k.r[0], [k.phi[0]], k.r[1], [k.phi[1]]])
        v = np.concatenate([k.r_d[0], [k.phi_d[0]], k.r_d[1], [k.phi_d[1]]])
        return q, v

    def readout(v_dot):
        return v_dot[[2, 5]], np.array([v_dot[0:2], v_dot[3:5]]), np.zeros(0)

    return PendulumCase(p, scene, state, readout)


def spatial_bodies(R0) -> PendulumCase:
    """Spatial bodies whose z axes are the joint axes, moving in the plane ``R0 (x, y)``."""
    p = LINKS
    scene = hx.Scene("double-pendulum-3d", dimension=3, gravity=R0 @ [0.0, -G, 0.0])
    scene.add(hx.scene.SpatialBody("link1", p.m1, _spatial_inertia(p.I1), com=[p.c1, 0.0, 0.0],
                                   rotation=R0),
              hx.scene.SpatialBody("link2", p.m2, _spatial_inertia(p.I2), com=[p.c2, 0.0, 0.0],
                                   position=_in_space(R0, [p.l1, 0.0]), rotation=R0),
              hx.scene.Revolute("shoulder", hx.scene.GROUND, "link1", origin=np.zeros(3),
                                rotation=R0),
              hx.scene.Revolute("elbow", "link1", "link2", origin=_in_space(R0, [p.l1, 0.0]),
                                rotation=R0))

    def state(k):
        q, v = [], []
        for i in range(2):
            q += [*_in_space(R0, k.r[i]), *euler_parameters(R0 @ rot_z(k.phi[i]))]
            v += [*_in_space(R0, k.r_d[i]), 0.0, 0.0, k.phi_d[i]]  # omega' in body axes
        return np.array(q), np.array(v)

    def readout(v_dot):
        a = [R0.T @ v_dot[0:3], R0.T @ v_dot[6:9]]
        # body-axes angular accelerations: z is the joint axis, x and y must stay zero
        out_of_plane = np.array([a[0][2], a[1][2], *v_dot[3:5], *v_dot[9:11]])
        return v_dot[[5, 11]], np.array([a[0][:2], a[1][:2]]), out_of_plane

    return PendulumCase(p, scene, state, readout)


def particles(R0=None) -> PendulumCase:
    """Point masses on massless rods (distance joints); planar when ``R0`` is None."""
    p = POINT_MASSES
    planar = R0 is None
    dim = 2 if planar else 3

    def place(xy):
        return np.asarray(xy, dtype=float) if planar else _in_space(R0, xy)

    gravity = [0.0, -G] if planar else R0 @ [0.0, -G, 0.0]
    scene = hx.Scene("point-pendulum", dimension=dim, gravity=gravity)
    zero = np.zeros(dim)
    scene.add(hx.scene.Particle("mass1", p.m1, position=place([p.l1, 0.0])),
              hx.scene.Particle("mass2", p.m2, position=place([p.l1 + p.l2, 0.0])),
              hx.scene.Distance("rod1", hx.scene.GROUND, "mass1", parent_frame=Placement(zero),
                                child_frame=Placement(zero), length=p.l1),
              hx.scene.Distance("rod2", "mass1", "mass2", parent_frame=Placement(zero),
                                child_frame=Placement(zero), length=p.l2))

    def state(k):
        return (np.concatenate([place(k.r[0]), place(k.r[1])]),
                np.concatenate([place(k.r_d[0]), place(k.r_d[1])]))

    def readout(v_dot):
        a = v_dot.reshape(2, dim)
        if not planar:
            a = a @ R0  # rows: R0^T a
        out_of_plane = a[:, 2] if not planar else np.zeros(0)
        return None, a[:, :2], out_of_plane

    return PendulumCase(p, scene, state, readout)


def _angular_from_points(p: Pendulum, k, r_dd):
    """Absolute angular accelerations of the rods from the point accelerations:
    ``phi_dd = (d x d_dd) / |d|^2`` for a rod vector ``d`` of constant length."""
    d = [k.r[0], k.r[1] - k.r[0]]
    d_dd = [r_dd[0], r_dd[1] - r_dd[0]]
    return np.array([(d[i][0] * d_dd[i][1] - d[i][1] * d_dd[i][0]) / (d[i] @ d[i])
                     for i in range(2)])


TILT = Rotation.from_rotvec([0.4, -0.9, 0.3]).as_matrix()
PENDULUM_CASES = {
    "planar-bodies": planar_bodies,
    "spatial-bodies": lambda: spatial_bodies(np.eye(3)),
    "spatial-bodies-tilted": lambda: spatial_bodies(TILT),
    "planar-particles": lambda: particles(None),
    "spatial-particles": lambda: particles(np.eye(3)),
    "spatial-particles-tilted": lambda: particles(TILT),
}


@pytest.mark.parametrize("case_name", list(PENDULUM_CASES))
def test_double_pendulum_matches_lagrange(case_name):
    case = PENDULUM_CASES[case_name]()
    p = case.params
    model = hx.assemble(case.scene)
    data = model.create_data()
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(6):
        theta = rng.uniform(-np.pi, np.pi, 2)
        theta_d = rng.uniform(-3.0, 3.0, 2)
        k = pendulum_kinematics(p, theta, theta_d)
        q, v = case.state(k)
        # the state is built from joint angles: it satisfies the joints (sanity of the setup)
        assert np.max(np.abs(model.call("phi", q=q))) < CONSISTENCY_ATOL
        assert np.max(np.abs(model.call("Phi_v", q=q) @ v)) < CONSISTENCY_ATOL

        theta_dd = lagrange_accelerations(p, theta, theta_d)
        ref = pendulum_kinematics(p, theta, theta_d, theta_dd)
        v_dot = hx.forward_dynamics(model, data, 0.0, q, v)
        phi_dd, r_dd, out_of_plane = case.readout(v_dot)
        if phi_dd is None:
            phi_dd = _angular_from_points(p, k, r_dd)
        # natural scales: g / l1 for angular, g for linear accelerations
        alpha_scale = np.max(np.abs(ref.phi_dd)) + G / p.l1
        accel_scale = np.max(np.abs(ref.r_dd)) + G
        assert_close(phi_dd[1] - phi_dd[0], theta_dd[1], PENDULUM_RTOL, alpha_scale,
                     f"{case_name}: relative angular acceleration")
        assert_close(phi_dd, ref.phi_dd, PENDULUM_RTOL, alpha_scale,
                     f"{case_name}: angular accelerations")
        assert_close(r_dd, ref.r_dd, PENDULUM_RTOL, accel_scale,
                     f"{case_name}: centre-of-mass accelerations")
        assert_close(out_of_plane, np.zeros_like(out_of_plane), PENDULUM_RTOL, accel_scale,
                     f"{case_name}: out-of-plane accelerations")


def test_lagrange_reference_is_not_trivial():
    """Guard on the reference itself: the Lagrange accelerations satisfy the energy balance
    d/dt (T + V) = 0 (checked by central differences of T + V along a short RK4 step)."""
    p = LINKS

    def energy(theta, theta_d):
        k = pendulum_kinematics(p, theta, theta_d)
        T = 0.5 * (p.m1 * k.r_d[0] @ k.r_d[0] + p.m2 * k.r_d[1] @ k.r_d[1]
                   + p.I1 * k.phi_d[0] ** 2 + p.I2 * k.phi_d[1] ** 2)
        return T + G * (p.m1 * k.r[0][1] + p.m2 * k.r[1][1])

    def f(x):
        return np.concatenate([x[2:], lagrange_accelerations(p, x[:2], x[2:])])

    x = np.array([0.7, -1.1, 1.5, -2.0])
    h = 1e-3
    for _ in range(20):
        k1 = f(x)
        k2 = f(x + h / 2 * k1)
        k3 = f(x + h / 2 * k2)
        k4 = f(x + h * k3)
        x_new = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        # RK4 local error ~h^5: energy drifts by far less than 1e-10 J per step
        assert abs(energy(x_new[:2], x_new[2:]) - energy(x[:2], x[2:])) < 1e-10
        x = x_new


# ================================================================== random spatial chains


@dataclass(frozen=True)
class Link:
    """One body of a serial chain and the revolute joint that carries it.

    Frames are (position, rotation) pairs. ``parent_frame`` is the joint frame in the parent's
    reference frame (world for the first link), ``child_frame`` the joint frame in this body's
    reference frame; the joint rotates the child by ``theta`` about ``axis`` (joint frame).
    ``inertia`` (about the centre of mass, reference axes) is what the reference uses; the
    scene gets it as ``inertia_given`` in the axes ``inertia_rotation``.
    """

    mass: float
    com: np.ndarray
    inertia: np.ndarray
    inertia_given: np.ndarray
    inertia_rotation: np.ndarray
    parent_frame: tuple[np.ndarray, np.ndarray]
    child_frame: tuple[np.ndarray, np.ndarray]
    axis: np.ndarray  # unit
    axis_given: np.ndarray  # what the scene gets: any length


def random_chain(rng, n: int) -> list[Link]:
    links = []
    for _ in range(n):
        mass = rng.uniform(0.5, 2.0)
        # a solid ellipsoid's principal moments are physical (triangle inequality holds)
        a, b, c = rng.uniform(0.05, 0.35, 3)
        moments = mass / 5 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
        R_principal = random_rotation(rng)
        given = R_principal @ np.diag(moments) @ R_principal.T  # full, non-diagonal
        R_inertia = random_rotation(rng)
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        links.append(Link(
            mass=mass,
            com=rng.uniform(-0.3, 0.3, 3),
            inertia=R_inertia @ given @ R_inertia.T,
            inertia_given=given,
            inertia_rotation=R_inertia,
            parent_frame=(rng.uniform(-0.5, 0.5, 3), random_rotation(rng)),
            child_frame=(rng.uniform(-0.3, 0.3, 3), random_rotation(rng)),
            axis=axis,
            axis_given=axis * rng.uniform(0.3, 3.0),
        ))
    return links


def chain_motion(links, theta, theta_d, theta_dd):
    """Forward recursion, world components. Per link: joint origin ``o``, joint frame ``Rj``,
    world axis ``s``, body rotation ``R`` and reference origin ``x``, centre of mass ``r``, its
    velocity ``v`` and acceleration ``a``, angular velocity ``w`` and acceleration ``alpha``."""
    R_prev, x_prev, r_prev = np.eye(3), np.zeros(3), np.zeros(3)
    w_prev, alpha_prev, v_prev, a_prev = (np.zeros(3) for _ in range(4))
    out = []
    for k, link in enumerate(links):
        pj, Rpj = link.parent_frame
        pc, Rc = link.child_frame
        o = x_prev + R_prev @ pj
        Rj = R_prev @ Rpj @ rodrigues(link.axis, theta[k])
        s = R_prev @ Rpj @ link.axis
        R = Rj @ Rc.T
        x = o - R @ pc
        r = x + R @ link.com
        w = w_prev + s * theta_d[k]
        alpha = alpha_prev + s * theta_dd[k] + np.cross(w_prev, s) * theta_d[k]
        d_prev, d = o - r_prev, r - o
        v_o = v_prev + np.cross(w_prev, d_prev)
        a_o = a_prev + np.cross(alpha_prev, d_prev) + np.cross(w_prev, np.cross(w_prev, d_prev))
        v = v_o + np.cross(w, d)
        a = a_o + np.cross(alpha, d) + np.cross(w, np.cross(w, d))
        out.append(SimpleNamespace(o=o, Rj=Rj, s=s, R=R, x=x, r=r, w=w, alpha=alpha, v=v, a=a))
        R_prev, x_prev, r_prev = R, x, r
        w_prev, alpha_prev, v_prev, a_prev = w, alpha, v, a
    return out


def rnea(links, theta, theta_d, theta_dd, gravity):
    """Recursive Newton-Euler: joint torques ``tau`` and, per joint, the force ``f`` and the
    moment ``n`` about the joint origin exerted by body k-1 (or the ground) on body k (world
    components), for the given joint motion."""
    motion = chain_motion(links, theta, theta_d, theta_dd)
    n_links = len(links)
    f, n, tau = np.zeros((n_links, 3)), np.zeros((n_links, 3)), np.zeros(n_links)
    for k in reversed(range(n_links)):
        m, link = motion[k], links[k]
        J = m.R @ link.inertia @ m.R.T
        inertial = link.mass * (m.a - gravity)  # m a - m g
        f[k] = inertial
        n[k] = J @ m.alpha + np.cross(m.w, J @ m.w) + np.cross(m.r - m.o, inertial)
        if k + 1 < n_links:
            f[k] += f[k + 1]
            n[k] += n[k + 1] + np.cross(motion[k + 1].o - m.o, f[k + 1])
        tau[k] = m.s @ n[k]
    return tau, f, n, motion


def free_chain_accelerations(links, theta, theta_d, gravity, tau):
    """Joint accelerations of the chain under joint torques ``tau``: ``M theta_dd = tau - h``
    with ``M`` from unit accelerations and ``h`` the RNEA torques at zero acceleration."""
    n_links = len(links)
    zero = np.zeros(n_links)
    M = np.column_stack([rnea(links, theta, zero, e, np.zeros(3))[0]
                         for e in np.eye(n_links)])
    h = rnea(links, theta, theta_d, zero, gravity)[0]
    return np.linalg.solve(M, tau - h)


def chain_scene(links, gravity, efforts=None, laws=None) -> hx.Scene:
    """The chain as a scene; bodies drawn at zero joint angles (their poses are only the
    initial guess: both joint frames are given in body coordinates)."""
    scene = hx.Scene("chain", dimension=3, gravity=gravity)
    rest = chain_motion(links, *(np.zeros(len(links)),) * 3)
    for k, (link, m) in enumerate(zip(links, rest, strict=True)):
        scene.add(hx.scene.SpatialBody(f"b{k}", link.mass, link.inertia_given, com=link.com,
                                       position=m.x, rotation=m.R,
                                       inertia_rotation=link.inertia_rotation))
    for k, link in enumerate(links):
        scene.add(hx.scene.Revolute(f"j{k}", hx.scene.GROUND if k == 0 else f"b{k - 1}", f"b{k}",
                                    parent_frame=Placement(*link.parent_frame),
                                    child_frame=Placement(*link.child_frame), axis=link.axis_given))
    for k, value in enumerate(efforts if efforts is not None else []):
        scene.add(hx.scene.JointEffort(f"motor{k}", f"j{k}", float(value)))
    for k, law in enumerate(laws if laws is not None else []):
        scene.add(hx.scene.JointDriver(f"drive{k}", f"j{k}", law))
    return scene


def engine_state(motion):
    """``q = (r, p)`` and ``v = (r_dot, omega')`` per body, ``omega'`` in body axes."""
    q = np.concatenate([np.concatenate([m.r, euler_parameters(m.R)]) for m in motion])
    v = np.concatenate([np.concatenate([m.v, m.R.T @ m.w]) for m in motion])
    return q, v


def engine_accelerations(motion):
    """``v_dot = (a, omega'_dot)`` with ``omega'_dot = R^T alpha`` (the body-axes derivative)."""
    return np.concatenate([np.concatenate([m.a, m.R.T @ m.alpha]) for m in motion])


def check_wrenches(model, q, data, links, tau, f, n, motion, what):
    """The engine's joint wrenches against the RNEA forces and moments about the joint
    origins, in the joint frames and in world axes; the joint frames themselves too."""
    wrenches = hx.joint_wrenches(model, data)
    world = hx.joint_wrenches(model, data, frame="world")
    length_scale = 1.0 + max(np.linalg.norm(m.o) for m in motion)
    f_scale = np.max(np.abs(f))
    n_scale = np.max(np.abs(n))
    for k, joint in enumerate(model.joints):
        m = motion[k]
        origin, R = joint_origin(model, q, joint)
        assert_close(origin, m.o, CHAIN_RTOL, length_scale, f"{what}: origin of {joint.name}")
        assert_close(R, m.Rj, CHAIN_RTOL, 1.0, f"{what}: joint frame of {joint.name}")
        assert_close(wrenches.force[k], m.Rj.T @ f[k], CHAIN_RTOL, f_scale,
                     f"{what}: force at {joint.name} (joint frame)")
        assert_close(wrenches.torque[k], m.Rj.T @ n[k], CHAIN_RTOL, n_scale,
                     f"{what}: moment at {joint.name} (joint frame)")
        assert_close(world.force[k], f[k], CHAIN_RTOL, f_scale,
                     f"{what}: force at {joint.name} (world)")
        assert_close(world.torque[k], n[k], CHAIN_RTOL, n_scale,
                     f"{what}: moment at {joint.name} (world)")
        # the axial moment is the torque the joint transmits: RNEA's tau
        assert_close(wrenches.effort[k], tau[k], CHAIN_RTOL, n_scale,
                     f"{what}: effort at {joint.name}")
    return wrenches


CHAIN_SIZES = [2, 3, 4, 5]


@pytest.mark.parametrize("n_links", CHAIN_SIZES)
def test_free_chain_matches_recursive_model(n_links):
    rng = np.random.default_rng(RNG_SEED + n_links)
    links = random_chain(rng, n_links)
    gravity = np.array([0.0, 0.0, -G])
    efforts = rng.uniform(-2.0, 2.0, n_links)  # N m, constant actuator torques
    model = hx.assemble(chain_scene(links, gravity, efforts=efforts))
    data = model.create_data()
    for trial in range(3):
        theta = rng.uniform(-np.pi, np.pi, n_links)
        theta_d = rng.uniform(-2.0, 2.0, n_links)
        state = chain_motion(links, theta, theta_d, np.zeros(n_links))
        q, v = engine_state(state)
        assert np.max(np.abs(model.call("phi", q=q))) < CONSISTENCY_ATOL
        assert np.max(np.abs(model.call("Phi_v", q=q) @ v)) < CONSISTENCY_ATOL

        theta_dd = free_chain_accelerations(links, theta, theta_d, gravity, efforts)
        tau, f, n, motion = rnea(links, theta, theta_d, theta_dd, gravity)
        assert_close(tau, efforts, 1e-12, np.max(np.abs(n)), "reference: RNEA closes")

        v_dot = hx.forward_dynamics(model, data, 0.0, q, v)
        expected = engine_accelerations(motion)
        assert_close(v_dot, expected, CHAIN_RTOL, None,
                     f"chain of {n_links}, state {trial}: body accelerations")
        # joint accelerations read back from the engine's body accelerations
        alpha = [m.R @ v_dot[6 * k + 3:6 * k + 6] for k, m in enumerate(motion)]
        theta_dd_engine = [m.s @ (alpha[k] - (alpha[k - 1] if k else 0.0))
                           for k, m in enumerate(motion)]
        assert_close(theta_dd_engine, theta_dd, CHAIN_RTOL, None,
                     f"chain of {n_links}, state {trial}: joint accelerations")
        check_wrenches(model, q, data, links, tau, f, n, motion,
                       f"chain of {n_links}, state {trial}")


@dataclass(frozen=True)
class Wave:
    """``offset + amplitude sin(omega t + phase)`` with its derivatives, and the same law for
    the engine (``Harmonic`` writes it as a cosine and a sine term)."""

    offset: float
    amplitude: float
    omega: float
    phase: float

    def __call__(self, t):
        s = self.omega * t + self.phase
        return (self.offset + self.amplitude * np.sin(s), self.amplitude * self.omega * np.cos(s),
                -self.amplitude * self.omega**2 * np.sin(s))

    def law(self):
        return hx.scene.Harmonic(offset=self.offset, cos=[self.amplitude * np.sin(self.phase)],
                                 sin=[self.amplitude * np.cos(self.phase)],
                                 frequency=self.omega / (2 * np.pi))


@pytest.mark.parametrize("n_links", [2, 4])
def test_driven_chain_matches_recursive_model(n_links):
    """All joints driven: the engine assembles the prescribed configuration, and its joint
    wrenches (effort = -lambda of the driver) are the RNEA forces."""
    rng = np.random.default_rng(RNG_SEED + 100 + n_links)
    links = random_chain(rng, n_links)
    gravity = np.array([1.2, -0.8, -G])
    waves = [Wave(rng.uniform(-0.3, 0.3), rng.uniform(0.2, 0.6), rng.uniform(2.0, 6.0),
                  rng.uniform(0, 2 * np.pi)) for _ in range(n_links)]
    model = hx.assemble(chain_scene(links, gravity, laws=[w.law() for w in waves]))
    data = model.create_data()
    for t in (0.0, 0.37, 1.21):
        theta, theta_d, theta_dd = (np.array(x) for x in zip(*(w(t) for w in waves),
                                                              strict=True))
        tau, f, n, motion = rnea(links, theta, theta_d, theta_dd, gravity)
        q, v = hx.consistent_state(model, data, t)
        for k, m in enumerate(motion):
            body = model.bodies[k]
            assert_close(q[body.q][:3], m.r, CHAIN_RTOL, 1.0, f"t={t}: position of b{k}")
            assert_close(rotation_from_parameters(q[body.q][3:]), m.R, CHAIN_RTOL, 1.0,
                         f"t={t}: rotation of b{k}")
        q_ref, v_ref = engine_state(motion)
        assert_close(v, v_ref, CHAIN_RTOL, None, f"t={t}: velocities")
        v_dot = hx.forward_dynamics(model, data, t, q, v)
        assert_close(v_dot, engine_accelerations(motion), CHAIN_RTOL, None,
                     f"t={t}: accelerations")
        wrenches = check_wrenches(model, q, data, links, tau, f, n, motion, f"t={t}")
        efforts = hx.driver_efforts(model, data)
        for driver in model.drivers:
            joint = model.joints[driver.joint]
            assert efforts[driver.name] == -data.lam[driver.row]
            assert_close(efforts[driver.name], wrenches.effort[joint.index], 1e-12,
                         np.max(np.abs(n)), f"t={t}: {driver.name} effort")
