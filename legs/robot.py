"""The hexapod: six legs attached by prefix (``L1`` ... ``R3``) to a trunk fixed in the world.

Each leg is :func:`legs.leg.leg_scene` placed at its thorax-coxa point (an estimate [E], scaled);
the trunk's reference frame is its centre of mass (x forward, y left, z up). With a gait, every
joint is driven and each foot carries the ground's reaction during its stance (the prescribed
generalized forces of Dumitru, Marin and Margine); the trunk is held, so the joints' loads are those
of a robot walking at constant height and speed.

:func:`hexapod_standing` is the robot standing: a free trunk, every joint held by a constant
driver at the mid-stance pose, the feet pinned to the ground, so that the feet's forces are
statically indeterminate (redundant rows).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from hexapod import (
    GROUND,
    AppliedForce,
    Constant,
    Fixed,
    Placement,
    Scene,
    SpatialBody,
    Spherical,
    rotation_about_axis,
)
from legs.cockroach import MODEL_SCALE, SEGMENTS, STRIDE_PERIOD, THC_POINT_MM, TRUNK, bracket
from legs.gait import GAITS, LEG_NAMES, leg_of
from legs.leg import JOINTS, leg_geometry, leg_scene
from legs.stepping import SOLVED_JOINTS, path_targets, solve_joints

GRAVITY = 9.81


def robot_mass(scale: float = MODEL_SCALE) -> float:
    """Trunk plus six legs (kg)."""
    legs = sum(2 * (sum(s.scaled(scale)[1] for s in SEGMENTS[leg])
                    + 2 * bracket(leg).scaled(scale)[1]) for leg in SEGMENTS)
    return TRUNK["mass_g"] * 1e-3 * scale**3 + legs


def robot_weight(scale: float = MODEL_SCALE) -> float:
    return robot_mass(scale) * GRAVITY


def hexapod_scene(gait: str | None = "tripod", period: float = STRIDE_PERIOD,
                  scale: float = MODEL_SCALE, loads: bool = True, name: str = "hexapod") -> Scene:
    """Six legs on a fixed trunk; with ``gait``, driven and (with ``loads``) loaded in stance."""
    scene = Scene(name, dimension=3, length_unit="m")
    scene.add(SpatialBody("trunk", TRUNK["mass_g"] * 1e-3 * scale**3,
                          np.array(TRUNK["inertia"]) * scale**5))
    scene.add(Fixed("trunk_hold", "ground", "trunk"))
    pattern = GAITS[gait] if gait else None
    for leg in LEG_NAMES:
        position, side = leg_of(leg)
        x, y, z = THC_POINT_MM[position]
        point = np.array([x, y if side == "L" else -y, z]) * 1e-3 * scale
        laws = pattern.joint_laws(leg, period) if pattern else None
        scene.attach(leg_scene(position, side, scale, laws), leg, base="trunk",
                     placement=Placement(point))
        if pattern and loads:
            scene.add(AppliedForce(f"{leg}/ground_reaction", f"{leg}/tarsus",
                                   pattern.stance_load(leg, robot_weight(scale), period),
                                   point="foot"))
    return scene


def hexapod_walking() -> Scene:
    """Built-in ``hexapod``: the six-legged robot at 20:1, trunk held, 18 driven joints in a
    tripod gait, the ground's reactions on the feet in stance."""
    return hexapod_scene()


#: The order in which feet are put on the ground by :func:`hexapod_standing`: a tripod first.
STANDING_FEET = ("L1", "R2", "L3", "R1", "L2", "R3")


def standing_pose(position: str, scale: float = MODEL_SCALE) -> dict[str, float]:
    """Joint angles (rad) of a ``front``, ``middle`` or ``hind`` leg with its foot at the
    middle of its tripod stance line, on the ground (``GROUND_Z_MM`` below the trunk's centre of
    mass): ``thc_levation``, ``coxa_rotation`` and ``tita`` at zero (their gait laws' values at
    mid-stance), the others by inverse kinematics (:func:`legs.stepping.solve_joints`). The
    right legs take the same angles (their axes mirror the left's)."""
    duty = GAITS["tripod"].duty
    geometry = leg_geometry(position, "L", scale)
    target = path_targets(position, np.array([1.0 - duty / 2]), duty, scale)
    solved = tuple(JOINTS.index(j) for j in SOLVED_JOINTS)
    angles = solve_joints(geometry, target, np.zeros((1, 6)), solved)[0]
    return dict(zip(JOINTS, (float(a) for a in angles), strict=True))


def standing_feet(scale: float = MODEL_SCALE) -> dict[str, np.ndarray]:
    """Where each foot stands (m, trunk frame = world at the standing pose)."""
    duty = GAITS["tripod"].duty
    out = {}
    for leg in LEG_NAMES:
        position, side = leg_of(leg)
        foot = path_targets(position, np.array([1.0 - duty / 2]), duty, scale)[0]
        thc = np.array(THC_POINT_MM[position]) * 1e-3 * scale
        if side == "R":
            foot[1], thc[1] = -foot[1], -thc[1]
        out[leg] = foot + thc
    return out


def posed(scene: Scene, angles: dict[str, float]) -> Scene:
    """A copy of a chain ``scene`` (joints in tree order, revolute) with its bodies moved to
    the pose of the joint ``angles``: the joint frames are kept on the bodies as they are at the
    rest pose, so the angles still count from it, and only the initial guess changes."""
    out = Scene(scene.name, scene.dimension, scene.length_unit)
    out.gravity = scene.gravity
    poses = {GROUND: Placement.identity(3)}
    joints = []
    for joint in scene.joints.values():
        parent_frame, child_frame = scene.joint_frames(joint)
        turn = Placement(np.zeros(3), rotation_about_axis(joint.axis, angles.get(joint.name,
                                                                                 0.0)))
        poses[joint.child] = poses[joint.parent] @ parent_frame @ turn @ child_frame.inverse()
        joints.append(replace(joint, origin=None, rotation=None, parent_frame=parent_frame,
                              child_frame=child_frame))
    for body in scene.bodies.values():
        pose = poses[body.name]
        out.add(replace(body, position=pose.position, rotation=pose.rotation))
    out.add(*joints, *scene.drivers.values(), *scene.forces.values())
    return out


def hexapod_standing(feet: int = 6, scale: float = MODEL_SCALE,
                     name: str = "hexapod-standing") -> Scene:
    """The robot standing still on its feet, every joint held: redundant constraints.

    A free trunk (no hold), every joint of every leg held at :func:`standing_pose` by a constant
    driver, and ``feet`` feet (3 to 6, in the order of :data:`STANDING_FEET`: a tripod first)
    pinned to the ground by spherical joints at :func:`standing_feet` (all on the plane
    ``z = GROUND_Z_MM``). With all joints held each leg is rigid, three feet already fix the
    trunk, and every further foot adds 3 redundant rows: ``3 feet - 6`` in all (12 with six
    feet), the feet's forces statically indeterminate (the engine shares them by its
    least-wrench policy). Under gravity nothing moves.

    The bodies start at the standing pose (:func:`posed`); the joint angles count from the rest
    pose, as in the walking scenes."""
    if not 3 <= feet <= 6:
        raise ValueError(f"feet must be 3 to 6, got {feet}")
    scene = Scene(name, dimension=3, length_unit="m")
    scene.add(SpatialBody("trunk", TRUNK["mass_g"] * 1e-3 * scale**3,
                          np.array(TRUNK["inertia"]) * scale**5))
    poses = {p: standing_pose(p, scale) for p in ("front", "middle", "hind")}
    for leg in LEG_NAMES:
        position, side = leg_of(leg)
        x, y, z = THC_POINT_MM[position]
        point = np.array([x, y if side == "L" else -y, z]) * 1e-3 * scale
        laws = {joint: Constant(angle) for joint, angle in poses[position].items()}
        scene.attach(posed(leg_scene(position, side, scale, laws), poses[position]), leg,
                     base="trunk", placement=Placement(point))
    standing = standing_feet(scale)
    for leg in STANDING_FEET[:feet]:
        scene.add(Spherical(f"{leg}/ground", "ground", f"{leg}/tarsus",
                            parent_frame=Placement(standing[leg]), child_frame="foot"))
    return scene
