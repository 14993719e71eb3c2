"""The mass-ratio cases: bodies whose masses differ by a factor of a million.

* :func:`mass_ratio`: a cockroach front leg whose three-axis thorax-coxa joint is made of two
  nearly massless links, against its five-degree-of-freedom Lagrange equations (Kane);
* :func:`mass_ratio_pendulum`: a double pendulum with a nearly massless lower rod, against
  its Lagrange equations written out.
"""

from __future__ import annotations

import numpy as np

from hexapod.benchmarks import jets
from hexapod.benchmarks.reference import Case, G, MinimalModel, Trajectory, minimal_reference
from hexapod.scene import PlanarBody, Revolute, Scene, SpatialBody

#: The front leg's segments at 20:1 (lengths m, radii m, masses kg), from the cockroach data of
#: legs/cockroach.py (natural scale: coxa 5 mm, 1 mm, 11.98 mg; trochanter + femur 7.5 mm, 0.55 mm,
#: 11.45 mg; tibia 5 mm, 0.35 mm, 2.66 mg; lengths x 20, masses x 8000). Rest pose: coxa 40 degrees
#: below the horizontal, femur horizontal, tibia 60 degrees below, in a vertical plane along +y.
LEG_SEGMENTS = {"coxa": (0.10, 0.020, 0.09584, 40.0), "femur": (0.15, 0.011, 0.09160, 0.0),
                "tibia": (0.10, 0.007, 0.02128, 60.0)}


def _cylinder(length, radius, mass) -> np.ndarray:
    """Principal inertia of a solid cylinder along x."""
    transverse = mass * (3 * radius**2 + length**2) / 12
    return np.array([mass * radius**2 / 2, transverse, transverse])


def _leg_geometry(ratio: float):
    """Rest-pose joint points and axes, bodies (mass, inertia in world axes at rest, centre of
    mass) of the chain ground -> link_1 -> link_2 -> coxa -> femur -> tibia."""
    def direction(deg):
        a = np.radians(deg)
        return np.array([0.0, np.cos(a), -np.sin(a)])

    points, frames, bodies = [np.zeros(3)] * 3, [], {}
    coxa_moments = _cylinder(*LEG_SEGMENTS["coxa"][:2], LEG_SEGMENTS["coxa"][2])
    tiny = (ratio * LEG_SEGMENTS["coxa"][2], np.diag(ratio * coxa_moments), np.zeros(3))
    bodies["link_1"] = bodies["link_2"] = tiny
    point = np.zeros(3)
    for name, (length, radius, mass, deg) in LEG_SEGMENTS.items():
        x = direction(deg)
        z = np.array([1.0, 0.0, 0.0])
        S = np.column_stack([x, np.cross(z, x), z])  # segment axes: x along it
        inertia = S @ np.diag(_cylinder(length, radius, mass)) @ S.T
        bodies[name] = (mass, inertia, point + 0.5 * length * x)
        frames.append(S)
        point = point + length * x
        points.append(point)
    axes = [np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]), direction(40.0),
            np.array([1.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])]
    return points, axes, frames, bodies


def mass_ratio(ratio: float = 1e-6, *, t_end: float = 0.5) -> Case:
    """A cockroach front leg at 20:1 (:data:`LEG_SEGMENTS`) with its three-axis thorax-coxa
    joint made of two zero-length links whose mass and inertia are ``ratio`` times the
    coxa's: revolute joints about the vertical, the leg plane's normal and the coxa, then the
    coxa-trochanter and femur-tibia joints (normal to the leg plane). Released at rest under
    gravity from the rest pose, its five joints free.

    Reference: Lagrange's equations in the five joint angles (Kane, the rest pose's axes
    turned by the joints before them), DOP853 at 1e-12. The mass matrix of the absolute
    coordinates spans ``1 / ratio`` (x the coxa's own spread); the joint-coordinate one
    does not."""
    points, axes, frames, bodies = _leg_geometry(ratio)
    chain = ("link_1", "link_2", "coxa", "femur", "tibia")
    scene = Scene(f"mass-ratio-leg-{ratio:.0e}", dimension=3)
    scene.gravity = np.array([0.0, 0.0, -G])
    for k, name in enumerate(chain):
        mass, inertia, com = bodies[name]
        if k < 2:
            scene.add(SpatialBody(name, mass, np.diag(inertia), position=com))
        else:
            S = frames[k - 2]
            scene.add(SpatialBody(name, mass, np.diag(S.T @ inertia @ S), position=com,
                                  rotation=S))
    joints = ("thc_1", "thc_2", "thc_3", "ctr", "fti")
    parents = ("ground",) + chain[:-1]
    for k, joint in enumerate(joints):
        scene.add(Revolute(joint, parents[k], chain[k], origin=points[k], axis=axes[k]))

    def chain_kinematics(x):
        R_parent = jets.Jet.constant(np.eye(3))
        origin = jets.Jet.constant(np.zeros(3))
        frames_out = {}
        for k, name in enumerate(chain):
            if k > 0:
                origin = origin + R_parent @ (points[k] - points[k - 1])
            R = R_parent @ jets.rotation(axes[k], x[k])
            frames_out[name] = (origin + R @ (bodies[name][2] - points[k]), R)
            R_parent = R
        return frames_out, {}

    model = MinimalModel(chain_kinematics, {n: bodies[n][:2] for n in chain}, [0.0, 0.0, -G])
    observed = ("coxa", "femur", "tibia")
    reference, accelerations = minimal_reference(model, np.zeros(5), np.zeros(5), t_end,
                                                  observed, 3)
    return Case(scene.name, scene, t_end,
                f"two links of {ratio:.0e} times the coxa's mass and inertia in a 3-axis "
                "joint: a mass matrix spanning that ratio", "mass-ratio", observed, reference,
                accelerations, length=0.35, dof=5, counted_dof=5,
                source="cockroach front leg at 20:1 (the segment data of "
                       "legs/cockroach.py); layout A's zero-length links")


def mass_ratio_pendulum(ratio: float = 1e-6, *, t_end: float = 5.0) -> Case:
    """A planar double pendulum of uniform rods, 1 m each: the upper one 1 kg, the lower
    ``ratio`` kg, released at rest from 1 rad and 2 rad (from the downward vertical).

    Reference: Lagrange's equations of the double pendulum written out by hand,
    ``M(th) th'' = f(th, th')``, DOP853 at 1e-12."""
    m1, m2, l1, l2 = 1.0, ratio, 1.0, 1.0
    I1, I2 = m1 * l1**2 / 12, m2 * l2**2 / 12
    th0 = np.array([1.0, 2.0])
    scene = Scene(f"mass-ratio-pendulum-{ratio:.0e}", dimension=2)
    elbow = l1 * np.array([np.sin(th0[0]), -np.cos(th0[0])])
    u2 = np.array([np.sin(th0[1]), -np.cos(th0[1])])
    scene.add(PlanarBody("upper", m1, I1, position=elbow / 2, angle=th0[0] - np.pi / 2))
    scene.add(PlanarBody("lower", m2, I2, position=elbow + u2 * l2 / 2,
                         angle=th0[1] - np.pi / 2))
    scene.add(Revolute("shoulder", "ground", "upper", origin=[0.0, 0.0]))
    scene.add(Revolute("elbow", "upper", "lower", origin=elbow))
    c1, c2 = l1 / 2, l2 / 2

    def accelerations_of(th, thd):
        d = th[0] - th[1]
        M = np.array([[I1 + m1 * c1**2 + m2 * l1**2, m2 * l1 * c2 * np.cos(d)],
                      [m2 * l1 * c2 * np.cos(d), I2 + m2 * c2**2]])
        f = np.array([-m2 * l1 * c2 * np.sin(d) * thd[1] ** 2 - (m1 * c1 + m2 * l1) * G
                      * np.sin(th[0]),
                      m2 * l1 * c2 * np.sin(d) * thd[0] ** 2 - m2 * c2 * G * np.sin(th[1])])
        return np.linalg.solve(M, f)

    def positions(th):
        e = l1 * np.array([np.sin(th[0]), -np.cos(th[0])])
        return np.concatenate([e / 2, e + l2 / 2 * np.array([np.sin(th[1]), -np.cos(th[1])])])

    reference = Trajectory(lambda _t, y: np.concatenate([y[2:], accelerations_of(y[:2],
                                                                                 y[2:])]),
                            np.concatenate([th0, [0.0, 0.0]]), t_end, lambda y: positions(y[:2]))
    thdd = accelerations_of(th0, np.zeros(2))
    e1 = np.array([np.cos(th0[0]), np.sin(th0[0])])
    e2 = np.array([np.cos(th0[1]), np.sin(th0[1])])
    accelerations = {"upper": c1 * thdd[0] * e1, "lower": l1 * thdd[0] * e1 + c2 * thdd[1] * e2}
    return Case(scene.name, scene, t_end,
                f"double pendulum whose lower rod is {ratio:.0e} times lighter", "mass-ratio",
                ("upper", "lower"), reference, accelerations, length=2.0, dof=2, counted_dof=2)
