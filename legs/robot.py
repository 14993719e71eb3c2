"""The hexapod: six legs attached by prefix (``L1`` ... ``R3``) to a trunk.

Each leg is :func:`legs.leg.leg_scene` placed at its thorax-coxa point (an estimate [E], scaled);
the trunk's reference frame is its centre of mass (x forward, y left, z up).

**Walking** (``trunk="free"``, the built-in ``hexapod``): the trunk is a free body. Every joint
is driven by the gait's exact laws (:class:`legs.stepping.Stepping`: each foot on its path to
round-off), and each foot in stance is held at its foothold by a
:class:`hexapod.Contact` (no slip). The footholds are where the feet touch down when the trunk
walks straight ahead at the gait's speed, level, from the origin at ``t = 0`` at the height that
puts the ground at ``z = 0``; the trunk's motion itself is not prescribed but follows from the
legs and the feet in stance. Three or more feet are always down, so the ground forces are shared
by the scene's policy (``hexapod.GroundForces``).

**Bench-top** (``trunk="held"``): the trunk is welded to the world, every joint driven by the
gait's harmonic laws and each foot in stance loaded by an invented ``sin^2`` pulse (the
prescribed generalized forces of Dumitru, Marin and Margine): the loads of a robot walking at
constant height and speed, as far as the pulses are right.

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
    Contact,
    Fixed,
    GroundForces,
    Placement,
    Scene,
    SpatialBody,
    Spherical,
    rotation_about_axis,
)
from legs.cockroach import (
    GROUND_Z_MM,
    MODEL_SCALE,
    SEGMENTS,
    STRIDE_PERIOD,
    THC_POINT_MM,
    TRUNK,
    bracket,
)
from legs.gait import GAITS, LEG_NAMES, leg_of
from legs.leg import JOINTS, leg_geometry, leg_scene
from legs.stepping import SOLVED_JOINTS, Stepping, exact_leg_motion, path_targets, solve_joints

GRAVITY = 9.81


def robot_mass(scale: float = MODEL_SCALE) -> float:
    """Trunk plus six legs (kg)."""
    legs = sum(2 * (sum(s.scaled(scale)[1] for s in SEGMENTS[leg])
                    + 2 * bracket(leg).scaled(scale)[1]) for leg in SEGMENTS)
    return TRUNK["mass_g"] * 1e-3 * scale**3 + legs


def robot_weight(scale: float = MODEL_SCALE) -> float:
    return robot_mass(scale) * GRAVITY


#: The walking robot's duty factor per gait: above 1/2, so that the load passes from one set
#: of feet to the next over a phase with more feet down (at exactly 1/2 it would jump).
WALKING_DUTY = {"tripod": 0.6, "tetrapod": 2 / 3, "wave": 5 / 6}


def hexapod_scene(gait: str | None = "tripod", period: float = STRIDE_PERIOD,
                  scale: float = MODEL_SCALE, loads: bool = True, name: str = "hexapod",
                  trunk: str = "held", duty: float | None = None,
                  ground: GroundForces | None = None) -> Scene:
    """The six-legged robot.

    Parameters
    ----------
    gait : {"tripod", "tetrapod", "wave"} or None
        Drives every joint (``None``: no drivers; ``trunk="held"`` only).
    trunk : {"held", "free"}
        ``held``: welded to the world, the feet loaded in stance by ``sin^2`` pulses (with
        ``loads``); ``free``: the walking robot, its feet held by contacts in stance.
    duty : float, optional
        Stance fraction of the free robot's cycle (default :data:`WALKING_DUTY`).
    ground : GroundForces, optional
        The free robot's ground-force policy (default: ``min-wrench``).
    """
    if trunk not in ("held", "free"):
        raise ValueError(f"trunk must be 'held' or 'free', got {trunk!r}")
    if trunk == "free":
        if gait is None:
            raise ValueError("a free trunk needs a gait (its legs carry it)")
        return _walking_scene(gait, period, scale, duty or WALKING_DUTY[gait], ground, name)
    scene = Scene(name, dimension=3, length_unit="m")
    scene.add(_trunk(scale))
    scene.add(Fixed("trunk_hold", "ground", "trunk"))
    pattern = GAITS[gait] if gait else None
    for leg in LEG_NAMES:
        laws = pattern.joint_laws(leg, period) if pattern else None
        scene.attach(leg_scene(leg_of(leg)[0], leg_of(leg)[1], scale, laws), leg,
                     base="trunk", placement=Placement(_thc_point(leg, scale)))
        if pattern and loads:
            scene.add(AppliedForce(f"{leg}/ground_reaction", f"{leg}/tarsus",
                                   pattern.stance_load(leg, robot_weight(scale), period),
                                   point="foot"))
    return scene


def _trunk(scale: float, position=(0.0, 0.0, 0.0)) -> SpatialBody:
    return SpatialBody("trunk", TRUNK["mass_g"] * 1e-3 * scale**3,
                       np.array(TRUNK["inertia"]) * scale**5, position=position)


def _thc_point(leg: str, scale: float) -> np.ndarray:
    """The leg's thorax-coxa point in the trunk frame (m)."""
    x, y, z = THC_POINT_MM[leg_of(leg)[0]]
    return np.array([x, y if leg_of(leg)[1] == "L" else -y, z]) * 1e-3 * scale


def _walking_scene(gait: str, period: float, scale: float, duty: float,
                   ground: GroundForces | None, name: str) -> Scene:
    pattern = replace(GAITS[gait], duty=duty)
    height = -GROUND_Z_MM * 1e-3 * scale  # the trunk's centre of mass above the ground
    speed = pattern.walking_speed(period, scale)
    scene = Scene(name, dimension=3, length_unit="m", ground=ground)
    scene.add(_trunk(scale, (0.0, 0.0, height)))
    for leg in LEG_NAMES:
        position, side = leg_of(leg)
        lift_off = pattern.lift_off[leg]
        laws = {joint: Stepping(position, joint, duty, period, lift_off) for joint in JOINTS}
        start = exact_leg_motion(position, duty, [(-lift_off) % 1.0])[0][0]
        sub = posed(leg_scene(position, side, scale, laws), dict(zip(JOINTS, start,
                                                                     strict=True)))
        scene.attach(sub, leg, base="trunk", placement=Placement(_thc_point(leg, scale)))
        # the stance that ends at lift_off * period began at (lift_off - duty) * period;
        # the foot then touched down where its path puts it, the trunk at speed * time
        touch_down = (lift_off - duty) * period
        foot = pattern.foot_targets(np.array([touch_down]), period, scale)[leg][0]
        foothold = foot + np.array([speed * touch_down, 0.0, height])
        scene.add(Contact(f"{leg}/ground", "ground", f"{leg}/tarsus", child_frame="foot",
                          period=period, duty=duty, lift_off=lift_off, foothold=foothold,
                          advance=[speed * period, 0.0, 0.0]))
    return scene


def hexapod_walking() -> Scene:
    """Built-in ``hexapod``: the six-legged robot at 20:1 walking in a tripod gait (duty 0.6):
    a free trunk, 18 joints driven so that each foot follows its path exactly, the feet in
    stance held to the ground by contacts, the ground forces shared by the least-wrench
    policy."""
    return hexapod_scene(trunk="free")


def hexapod_held() -> Scene:
    """Built-in ``hexapod-held``: the six-legged robot on a bench, trunk welded to the world,
    18 driven joints in a tripod gait, each foot loaded by a ``sin^2`` pulse in stance."""
    return hexapod_scene(trunk="held", name="hexapod-held")


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
