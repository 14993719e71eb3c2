"""The hexapod: six legs attached by prefix (``L1`` ... ``R3``) to a trunk.

Each leg is :func:`legs.leg.leg_scene` placed at its thorax-coxa point (an estimate [E], scaled);
the trunk's reference frame is its centre of mass (x forward, y left, z up).

**Walking** (``trunk="free"``, the built-in ``hexapod``): a robot description among others
(:func:`cockroach_description`, the same as ``data/robots/cockroach.toml``), walked by the path
every robot takes (:func:`legs.walker.robot_scene`): the trunk a free body whose pose is a guide
(level, straight ahead at the gait's speed, its centre of mass ``-GROUND_Z_MM`` above the ground
``z = 0``), each foot's path a guide (on its foothold in stance, stepping to the next in swing),
three joints of each leg following the guides as the engine's kinematics places them and the
other three the foot's lift and reach (:mod:`legs.stepping`), each foot in stance held at its
foothold by a :class:`hexapod.scene.Contact` (no slip). Three or more feet are always down, so
the ground forces are shared by the scene's policy (``hexapod.scene.GroundForces``).

**Bench-top** (``trunk="held"``): the trunk is welded to the world, every joint driven by the
gait's harmonic laws and each foot in stance loaded by an invented ``sin^2`` pulse (the
prescribed generalized forces of Dumitru, Marin and Margine): the loads of a robot walking at
constant height and speed, as far as the pulses are right.

:func:`hexapod_standing` is the robot standing: a free trunk, every joint held by a constant
driver at the mid-stance pose, the feet pinned to the ground, so that the feet's forces are
statically indeterminate (redundant rows).

**Design options**: the built-in builders (:func:`hexapod_walking`, :func:`hexapod_held`,
:func:`hexapod_standing`) take the parameters a robot designer varies as keyword-only arguments
whose defaults give the built-in scenes: the gait, its stride period or the walking speed, its
duty factor, the geometric scale, a payload at the trunk's centre of mass, and factors of the
segments' lengths (see :func:`hexapod_scene`). Each is checked, and a value out of its range
raises ``ValueError`` naming the argument and the range.
"""

from __future__ import annotations

import copy
import math
import threading
from collections import OrderedDict
from dataclasses import fields, replace
from pathlib import Path

import numpy as np

from hexapod import Scene
from hexapod.scene import (
    AppliedForce,
    Constant,
    Fixed,
    GroundForces,
    SpatialBody,
    Spherical,
)
from hexapod.spatial import Placement
from legs.cockroach import (
    FOOT_LIFT_MM,
    GAIT_LAWS,
    GROUND_Z_MM,
    MODEL_SCALE,
    SEGMENTS,
    STANCE_OFFSET_MM,
    STRIDE_PERIOD,
    THC_POINT_MM,
    TRUNK,
    bracket,
)
from legs.description import Foot, Gait, RobotDescription
from legs.gait import GAITS, LEG_NAMES, GaitPattern, leg_of
from legs.leg import JOINTS, NOMINAL_LENGTHS, SEGMENT_NAMES, leg_geometry, leg_scene
from legs.posing import posed
from legs.stepping import COUPLED_JOINTS, SAMPLES, leg_motion, path_targets
from legs.walker import robot_scene

GRAVITY = 9.81


def robot_mass(scale: float = MODEL_SCALE, *, lengths=None, payload: float = 0.0) -> float:
    """Trunk plus six legs (kg), the legs' segments' lengths multiplied by ``lengths`` (coxa,
    femur, tibia, tarsus; None: all 1), plus a ``payload`` (kg)."""
    factors = lengths or NOMINAL_LENGTHS
    legs = sum(2 * (sum(s.stretched(f).scaled(scale)[1]
                        for s, f in zip(SEGMENTS[leg], factors, strict=True))
                    + 2 * bracket(leg).scaled(scale)[1]) for leg in SEGMENTS)
    return TRUNK["mass_g"] * 1e-3 * scale**3 + legs + payload


def robot_weight(scale: float = MODEL_SCALE, *, lengths=None, payload: float = 0.0) -> float:
    """The weight (N) of :func:`robot_mass`."""
    return robot_mass(scale, lengths=lengths, payload=payload) * GRAVITY


#: The walking robot's duty factor per gait: above 1/2, so that the load passes from one set
#: of feet to the next over a phase with more feet down (at exactly 1/2 it would jump).
WALKING_DUTY = {"tripod": 0.6, "tetrapod": 2 / 3, "wave": 5 / 6}

# ------------------------------------------------------------------ design options


def check_number(name: str, value, low: float = -math.inf, high: float = math.inf, *,
                 closed_low: bool = False, closed_high: bool = False, unit: str = "") -> float:
    """``value`` as a float when it is a finite number in the range from ``low`` to ``high``
    (open ends unless ``closed_*``), else ``ValueError`` naming ``name`` and the range."""
    if low > -math.inf and high < math.inf:
        allowed = (f"in {'[' if closed_low else '('}{low:.6g}, {high:.6g}"
                   f"{']' if closed_high else ')'}")
    elif low > -math.inf:
        allowed = f"{'>=' if closed_low else '>'} {low:.6g}"
    else:
        allowed = f"{'<=' if closed_high else '<'} {high:.6g}"
    number = isinstance(value, (int, float, np.integer, np.floating)) \
        and not isinstance(value, (bool, np.bool_))
    x = float(value) if number else math.nan
    if not (math.isfinite(x) and (low <= x if closed_low else low < x)
            and (x <= high if closed_high else x < high)):
        raise ValueError(f"{name} must be a finite number {allowed}"
                         f"{f' ({unit})' if unit else ''}, got {value!r}")
    return x


def check_gait(gait) -> GaitPattern:
    """The pattern of ``gait``, else ``ValueError`` naming the gaits."""
    if not isinstance(gait, str) or gait not in GAITS:
        raise ValueError(f"gait must be one of {', '.join(map(repr, GAITS))}, got {gait!r}")
    return GAITS[gait]


def check_lengths(coxa_length, femur_length, tibia_length, tarsus_length) -> tuple | None:
    """The four segment length factors, checked (finite, > 0); None when all are 1."""
    factors = tuple(check_number(f"{name}_length", value, 0.0, unit="factor of its length")
                    for name, value in zip(SEGMENT_NAMES, (coxa_length, femur_length,
                                                           tibia_length, tarsus_length),
                                           strict=True))
    return None if factors == NOMINAL_LENGTHS else factors


def stride_period(pattern: GaitPattern | None, period, speed, scale: float) -> float:
    """The stride period (s): ``period`` or, given ``speed`` (m/s) instead, the period at which
    ``pattern`` walks at that speed (:meth:`legs.gait.GaitPattern.period_for_speed`); the
    built-in :data:`legs.cockroach.STRIDE_PERIOD` when neither is given."""
    if period is not None and speed is not None:
        raise ValueError(f"give period or speed, not both (got period={period!r}, "
                         f"speed={speed!r})")
    if speed is not None:
        speed = check_number("speed", speed, 0.0, unit="m/s, the trunk's walking speed")
        if pattern is None:
            raise ValueError("speed needs a gait (it sets the period through the gait)")
        return pattern.period_for_speed(speed, scale)
    if period is None:
        return STRIDE_PERIOD
    return check_number("period", period, 0.0, unit="s, the stride period")


def walking_pattern(gait: str, duty) -> GaitPattern:
    """The walking robot's pattern: ``gait`` with ``duty`` (default :data:`WALKING_DUTY`),
    which must keep three feet or more on the ground at every instant (and be at least
    1/2)."""
    pattern = check_gait(gait)
    if duty is None:
        return replace(pattern, duty=WALKING_DUTY[gait])
    least = max(0.5, pattern.least_duty(3) - 1e-12)  # (2/3: 0.66...67 there, 0.66...66 here)
    duty = check_number("duty", duty, least, 1.0, closed_low=True,
                        unit=f"stance fraction: the walking robot's {gait} gait keeps three "
                             "feet or more down at every instant")
    return replace(pattern, duty=duty)


def hexapod_scene(gait: str | None = "tripod", period: float | None = None,
                  scale: float = MODEL_SCALE, loads: bool = True, name: str = "hexapod",
                  trunk: str = "held", duty: float | None = None,
                  ground: GroundForces | None = None, *, speed: float | None = None,
                  payload: float = 0.0, coxa_length: float = 1.0, femur_length: float = 1.0,
                  tibia_length: float = 1.0, tarsus_length: float = 1.0,
                  step_height: float | None = None) -> Scene:
    """The six-legged robot.

    Parameters
    ----------
    gait : {"tripod", "tetrapod", "wave"} or None
        Drives every joint (``None``: no drivers; ``trunk="held"`` only).
    period : float, optional
        Stride period (s, > 0; default :data:`legs.cockroach.STRIDE_PERIOD`, 0.5 s). Give
        ``period`` or ``speed``, not both.
    scale : float
        Geometric scale (> 0; default :data:`legs.cockroach.MODEL_SCALE`, 20): lengths x scale,
        masses x scale^3.
    trunk : {"held", "free"}
        ``held``: welded to the world, the feet loaded in stance by ``sin^2`` pulses (with
        ``loads``); ``free``: the walking robot, its feet held by contacts in stance.
    duty : float, optional
        Stance fraction of the cycle. Free robot: default :data:`WALKING_DUTY`, and at least
        what keeps three feet down at every instant (1/2 for the tripod and the wave gait,
        2/3 for the tetrapod), below 1. Held robot: the gait's own (``GAITS[gait].duty``),
        in (0, 1).
    ground : GroundForces, optional
        The free robot's ground-force policy (default: ``min-wrench``).
    speed : float, optional
        The trunk's walking speed (m/s, > 0), instead of ``period``: the period is
        ``GaitPattern.walking_speed(1, scale) / speed`` (the speed is inversely proportional
        to the period; it depends on the duty factor and the scale).
    payload : float
        A point mass (kg, >= 0; default 0) at the trunk's centre of mass: it adds to the
        trunk's mass, not to its inertia about its centre of mass. The held robot's trunk is
        welded, so there it changes only the weight its feet's ``sin^2`` loads carry.
    coxa_length, femur_length, tibia_length, tarsus_length : float
        Factors (> 0; default 1) of every leg's segment lengths: each segment's mass follows
        its length (same cross-section and density), its inertias follow from both. Each foot's
        path keeps its definition in terms of the rest pose of the leg with the new lengths
        (:mod:`legs.stepping`); a leg that cannot follow it raises ``ValueError``.
    step_height : float, optional
        The free robot's feet's lift in swing (m, > 0; default ``FOOT_LIFT_MM``, scaled: 0.05
        m at scale 20); the held robot's joint laws are fitted to its own.

    Raises
    ------
    ValueError
        An option out of its range (the message names it and the range), or a leg that cannot
        reach its foot path.
    """
    if trunk not in ("held", "free"):
        raise ValueError(f"trunk must be 'held' or 'free', got {trunk!r}")
    scale = check_number("scale", scale, 0.0, unit="geometric scale")
    payload = check_number("payload", payload, 0.0, closed_low=True, unit="kg")
    lengths = check_lengths(coxa_length, femur_length, tibia_length, tarsus_length)
    if trunk == "free":
        if gait is None:
            raise ValueError("a free trunk needs a gait (its legs carry it)")
        pattern = walking_pattern(gait, duty)
        period = stride_period(pattern, period, speed, scale)
        if step_height is not None:
            step_height = check_number("step_height", step_height, 0.0, unit="m")
        return _walking_scene(pattern, period, scale, ground, name, payload, lengths,
                              step_height)
    if step_height is not None:
        raise ValueError("step_height is the walking robot's (trunk='free'): the held robot's "
                         "joint laws are fitted to its own feet's paths")
    pattern = None if gait is None else check_gait(gait)
    if duty is not None:
        if pattern is None:
            raise ValueError("duty needs a gait")
        pattern = replace(pattern, duty=check_number("duty", duty, 0.0, 1.0,
                                                     unit="stance fraction"))
    period = stride_period(pattern, period, speed, scale)
    scene = Scene(name, dimension=3, length_unit="m")
    scene.add(_trunk(scale, payload=payload))
    scene.add(Fixed("trunk_hold", "ground", "trunk"))
    weight = robot_weight(scale, lengths=lengths, payload=payload)
    for leg in LEG_NAMES:
        laws = pattern.joint_laws(leg, period, lengths) if pattern else None
        scene.attach(leg_scene(leg_of(leg)[0], leg_of(leg)[1], scale, laws, lengths=lengths),
                     leg, base="trunk", placement=Placement(_thc_point(leg, scale)))
        if pattern and loads:
            scene.add(AppliedForce(f"{leg}/ground_reaction", f"{leg}/tarsus",
                                   pattern.stance_load(leg, weight, period), point="foot"))
    return scene


def _trunk(scale: float, position=(0.0, 0.0, 0.0), payload: float = 0.0) -> SpatialBody:
    """The trunk, carrying ``payload`` (kg) at its centre of mass."""
    return SpatialBody("trunk", TRUNK["mass_g"] * 1e-3 * scale**3 + payload,
                       np.array(TRUNK["inertia"]) * scale**5, position=position,
                       payload=payload)


def _thc_point(leg: str, scale: float) -> np.ndarray:
    """The leg's thorax-coxa point in the trunk frame (m)."""
    x, y, z = THC_POINT_MM[leg_of(leg)[0]]
    return np.array([x, y if leg_of(leg)[1] == "L" else -y, z]) * 1e-3 * scale


def cockroach_body(scale: float = MODEL_SCALE, lengths: tuple | None = None,
                   payload: float = 0.0, name: str = "cockroach") -> Scene:
    """The robot's bodies and joints: a free trunk carrying ``payload`` (kg) and the six legs
    at their rest poses (joint angles zero), each at its thorax-coxa point, no driver; its
    segments' ``lengths`` as in :func:`hexapod_scene`."""
    scene = Scene(name, dimension=3, length_unit="m")
    scene.add(_trunk(scale, payload=payload))
    for leg in LEG_NAMES:
        position, side = leg_of(leg)
        scene.attach(leg_scene(position, side, scale, None, lengths=lengths), leg,
                     base="trunk", placement=Placement(_thc_point(leg, scale)))
    return scene


def cockroach_description(pattern: GaitPattern, period: float, scale: float = MODEL_SCALE,
                          name: str = "hexapod", payload: float = 0.0,
                          lengths: tuple | None = None,
                          ground: GroundForces | None = None,
                          step_height: float | None = None) -> RobotDescription:
    """The walking robot as a robot description (:mod:`legs.description`), the built-in one
    among others: its body (:func:`cockroach_body`), each foot the tarsus's end with its stance
    line ``STANCE_OFFSET_MM`` fore-aft of the rest pose's foot, the joints of
    ``legs.stepping.COUPLED_JOINTS`` following the foot through the cycle with the amplitudes
    of ``GAIT_LAWS``, the gait ``pattern`` (its lift-offs and duty) at ``period``, a stride of
    ``STANCE_LENGTH_MM`` over the duty, a lift of ``step_height`` (m; default
    ``FOOT_LIFT_MM``), the trunk level at
    ``-GROUND_Z_MM`` above the ground (all scaled), the ``ground``'s policy (default
    least-wrench)."""
    mm = 1e-3 * scale
    feet = {}
    for leg in LEG_NAMES:
        position, side = leg_of(leg)
        tarsus = leg_geometry(position, side, scale, lengths).lengths[3]
        feet[leg] = Foot(f"{leg}/tarsus", np.array([tarsus, 0.0, 0.0]),
                         np.array([STANCE_OFFSET_MM[position] * mm, 0.0]))
    amplitude = {joint: np.radians(a) for joint, a, _ in GAIT_LAWS}
    coupled = {f"*/{joint}": (follows, float(amplitude[joint]))
               for joint, follows in COUPLED_JOINTS.items()}
    gait = Gait(dict(pattern.lift_off), pattern.duty, period,
                pattern.walking_speed(period, scale) * period,
                FOOT_LIFT_MM * mm if step_height is None else step_height,
                trunk="level", height=-GROUND_Z_MM * mm)
    settings = {} if ground is None else {f.name: getattr(ground, f.name) for f in fields(ground)}
    return RobotDescription(name, Path(), "trunk", feet, {}, gait, settings, coupled=coupled,
                            body=cockroach_body(scale, lengths, payload, name))


#: Walking scenes built in this process, by their builder's arguments (the most recent
#: :data:`KEPT_SCENES`): building one walks the description and poses the robot by Newton's
#: method (0.4 s for the built-in robot), the same numbers each time.
_BUILT: OrderedDict[str, Scene] = OrderedDict()
_BUILT_LOCK = threading.Lock()
KEPT_SCENES = 8


def _walking_scene(pattern: GaitPattern, period: float, scale: float,
                   ground: GroundForces | None, name: str, payload: float = 0.0,
                   lengths: tuple | None = None, step_height: float | None = None) -> Scene:
    """The walking robot through the general path: its description walked by
    :func:`legs.walker.robot_scene`; a leg whose lengths cannot follow its path over the cycle
    is said first (``ValueError``). Built once per process for the same arguments (a copy of
    the first each time after: the caller may edit it)."""
    key = repr((pattern, period, scale, ground, name, payload, lengths, step_height))
    with _BUILT_LOCK:
        scene = _BUILT.get(key)
        if scene is not None:
            _BUILT.move_to_end(key)
            return copy.deepcopy(scene)
    scene = _walked_scene(pattern, period, scale, ground, name, payload, lengths, step_height)
    with _BUILT_LOCK:
        _BUILT[key] = copy.deepcopy(scene)
        while len(_BUILT) > KEPT_SCENES:
            _BUILT.popitem(last=False)
    return scene


def _walked_scene(pattern: GaitPattern, period: float, scale: float,
                  ground: GroundForces | None, name: str, payload: float,
                  lengths: tuple | None, step_height: float | None) -> Scene:
    """:func:`_walking_scene`, built."""
    if lengths is not None:
        tau = (np.arange(SAMPLES) + 0.5) / SAMPLES
        for position in ("front", "middle", "hind"):
            leg_motion(position, pattern.duty, tau, lengths)
    return robot_scene(cockroach_description(pattern, period, scale, name, payload, lengths,
                                             ground, step_height))


def hexapod_walking(*, gait: str = "tripod", period: float | None = None,
                    speed: float | None = None, duty: float | None = None,
                    scale: float = MODEL_SCALE, payload: float = 0.0, coxa_length: float = 1.0,
                    femur_length: float = 1.0, tibia_length: float = 1.0,
                    tarsus_length: float = 1.0, step_height: float | None = None) -> Scene:
    """Built-in ``hexapod``: the six-legged robot at 20:1 walking in a tripod gait (duty 0.6),
    as its robot description (data/robots/cockroach.toml): a free trunk, each foot on its path
    exactly as the engine's kinematics places its leg's 6 joints, the feet in stance held to the
    ground by contacts, the ground forces shared by the least-wrench policy.

    With no arguments, the built-in scene.

    Parameters
    ----------
    gait : {"tripod", "tetrapod", "wave"}
        Which legs swing together (default ``"tripod"``).
    period : float, optional
        Stride period (s, > 0; default 0.5). Give ``period`` or ``speed``, not both.
    speed : float, optional
        The trunk's walking speed (m/s, > 0) instead of ``period``: the period is then
        ``GaitPattern.walking_speed(1, scale) / speed`` (0.867 m/s at the defaults).
    duty : float, optional
        Stance fraction of each leg's cycle, below 1 and at least what keeps three feet down at
        every instant: [0.5, 1) for the tripod and the wave gait, [2/3, 1) for the tetrapod
        (default :data:`WALKING_DUTY`: 0.6, 2/3, 5/6).
    scale : float
        Geometric scale (> 0; default 20): lengths x scale, masses x scale^3.
    payload : float
        Point mass (kg, >= 0; default 0) carried at the trunk's centre of mass.
    coxa_length, femur_length, tibia_length, tarsus_length : float
        Factors (dimensionless, > 0; default 1) of every leg's segment lengths; masses follow
        the lengths. Each foot's path is defined from the rest pose of the leg with the new
        lengths (stance line ``STANCE_OFFSET_MM`` fore-aft of its rest foot, same ground,
        stride and lift); a leg that cannot follow it raises ``ValueError``.
    step_height : float, optional
        The feet's lift in swing (m, > 0; default 0.05 at scale 20: ``FOOT_LIFT_MM`` scaled).

    Raises
    ------
    ValueError
        An option out of its range (the message names it and its range), or a leg that
        cannot reach its foot path.
    """
    return hexapod_scene(gait, period, scale, trunk="free", duty=duty, speed=speed,
                         payload=payload, coxa_length=coxa_length, femur_length=femur_length,
                         tibia_length=tibia_length, tarsus_length=tarsus_length,
                         step_height=step_height)


def hexapod_held(*, gait: str = "tripod", period: float | None = None,
                 speed: float | None = None, duty: float | None = None,
                 scale: float = MODEL_SCALE, payload: float = 0.0, coxa_length: float = 1.0,
                 femur_length: float = 1.0, tibia_length: float = 1.0,
                 tarsus_length: float = 1.0) -> Scene:
    """Built-in ``hexapod-held``: the six-legged robot on a bench, trunk welded to the world,
    36 driven joints in a tripod gait, each foot loaded by a ``sin^2`` pulse in stance (its
    peak such that the feet carry the robot's weight on average).

    With no arguments, the built-in scene.

    Parameters
    ----------
    gait : {"tripod", "tetrapod", "wave"}
        Which legs swing together (default ``"tripod"``).
    period : float, optional
        Stride period (s, > 0; default 0.5). Give ``period`` or ``speed``, not both.
    speed : float, optional
        The walking speed (m/s, > 0) the laws stand for, instead of ``period``: the period is
        ``GaitPattern.walking_speed(1, scale) / speed``.
    duty : float, optional
        Stance fraction (in (0, 1); default the gait's own: 1/2, 2/3, 5/6 for the tripod,
        tetrapod and wave gait). Small values may put the swing out of the legs' reach
        (``ValueError``).
    scale : float
        Geometric scale (> 0; default 20).
    payload : float
        Point mass (kg, >= 0; default 0) at the trunk's centre of mass. The trunk is welded, so
        it changes only the weight the feet's ``sin^2`` loads carry.
    coxa_length, femur_length, tibia_length, tarsus_length : float
        Factors (dimensionless, > 0; default 1) of every leg's segment lengths; masses follow
        the lengths, the foot paths are defined from the new rest poses (as for
        :func:`hexapod_walking`).

    Raises
    ------
    ValueError
        An option out of its range (the message names it and its range), or a leg that
        cannot reach its foot path.
    """
    return hexapod_scene(gait, period, scale, trunk="held", name="hexapod-held", duty=duty,
                         speed=speed, payload=payload, coxa_length=coxa_length,
                         femur_length=femur_length, tibia_length=tibia_length,
                         tarsus_length=tarsus_length)


#: The order in which feet are put on the ground by :func:`hexapod_standing`: a tripod first.
STANDING_FEET = ("L1", "R2", "L3", "R1", "L2", "R3")


def standing_pose(position: str, scale: float = MODEL_SCALE,
                  lengths=None) -> dict[str, float]:
    """Joint angles (rad) of a ``front``, ``middle`` or ``hind`` leg with its foot at the
    middle of its tripod stance line, on the ground (``GROUND_Z_MM`` below the trunk's centre of
    mass): ``thc_levation``, ``coxa_rotation`` and ``tita`` at zero (their gait laws' values at
    mid-stance), the others where the engine's kinematics places the foot
    (:func:`legs.stepping.leg_motion`). The
    right legs take the same angles (their axes mirror the left's). The segments' lengths are
    multiplied by ``lengths`` (coxa, femur, tibia, tarsus; None: all 1)."""
    duty = GAITS["tripod"].duty
    angles = leg_motion(position, duty, [1.0 - duty / 2], lengths)[0][0]
    return dict(zip(JOINTS, (float(a) for a in angles), strict=True))


def standing_feet(scale: float = MODEL_SCALE, lengths=None) -> dict[str, np.ndarray]:
    """Where each foot stands (m, trunk frame = world at the standing pose)."""
    duty = GAITS["tripod"].duty
    out = {}
    for leg in LEG_NAMES:
        position, side = leg_of(leg)
        foot = path_targets(position, np.array([1.0 - duty / 2]), duty, scale, lengths)[0]
        thc = np.array(THC_POINT_MM[position]) * 1e-3 * scale
        if side == "R":
            foot[1], thc[1] = -foot[1], -thc[1]
        out[leg] = foot + thc
    return out


def hexapod_standing(feet: int = 6, scale: float = MODEL_SCALE,
                     name: str = "hexapod-standing", *, payload: float = 0.0,
                     coxa_length: float = 1.0, femur_length: float = 1.0,
                     tibia_length: float = 1.0, tarsus_length: float = 1.0) -> Scene:
    """Built-in ``hexapod-standing``: the robot standing still on its feet, every joint held:
    redundant constraints.

    With no arguments, the built-in scene.

    A free trunk (no hold), every joint of every leg held at :func:`standing_pose` by a constant
    driver, and ``feet`` feet (3 to 6, in the order of :data:`STANDING_FEET`: a tripod first)
    pinned to the ground by spherical joints at :func:`standing_feet` (all on the plane
    ``z = GROUND_Z_MM``). With all joints held each leg is rigid, three feet already fix the
    trunk, and every further foot adds 3 redundant rows: ``3 feet - 6`` in all (12 with six
    feet), the feet's forces statically indeterminate (the engine shares them by its
    least-wrench policy). Under gravity nothing moves.

    The bodies start at the standing pose (:func:`posed`); the joint angles count from the rest
    pose, as in the walking scenes.

    Parameters
    ----------
    feet : int
        How many feet are pinned to the ground (3 to 6; default 6).
    scale : float
        Geometric scale (> 0; default 20).
    name : str
        The scene's name.
    payload : float
        Point mass (kg, >= 0; default 0) carried at the trunk's centre of mass.
    coxa_length, femur_length, tibia_length, tarsus_length : float
        Factors (dimensionless, > 0; default 1) of every leg's segment lengths; masses follow
        the lengths. Each foot stands at the middle of its tripod stance line, defined from the
        rest pose of the leg with the new lengths (as for :func:`hexapod_walking`); a leg that
        cannot reach it raises ``ValueError``.

    Raises
    ------
    ValueError
        An option out of its range (the message names it and its range), or a leg that
        cannot reach its foothold.
    """
    if isinstance(feet, bool) or not isinstance(feet, (int, np.integer)) or not 3 <= feet <= 6:
        raise ValueError(f"feet must be 3 to 6, got {feet}")
    feet = int(feet)
    scale = check_number("scale", scale, 0.0, unit="geometric scale")
    payload = check_number("payload", payload, 0.0, closed_low=True, unit="kg")
    lengths = check_lengths(coxa_length, femur_length, tibia_length, tarsus_length)
    scene = Scene(name, dimension=3, length_unit="m")
    scene.add(SpatialBody("trunk", TRUNK["mass_g"] * 1e-3 * scale**3 + payload,
                          np.array(TRUNK["inertia"]) * scale**5))
    poses = {p: standing_pose(p, scale, lengths) for p in ("front", "middle", "hind")}
    for leg in LEG_NAMES:
        position, side = leg_of(leg)
        x, y, z = THC_POINT_MM[position]
        point = np.array([x, y if side == "L" else -y, z]) * 1e-3 * scale
        laws = {joint: Constant(angle) for joint, angle in poses[position].items()}
        scene.attach(posed(leg_scene(position, side, scale, laws, lengths=lengths),
                           poses[position]), leg, base="trunk", placement=Placement(point))
    standing = standing_feet(scale, lengths)
    for leg in STANDING_FEET[:feet]:
        scene.add(Spherical(f"{leg}/ground", "ground", f"{leg}/tarsus",
                            parent_frame=Placement(standing[leg]), child_frame="foot"))
    return scene
