"""Any legged robot walking: gaits for any number of legs, the feet's paths, and the scene.

A robot is its URDF and a small description (:mod:`legs.description`): the trunk, each foot
(a link and a point), a rest posture. Walking it needs no inverse kinematics of its own: the
trunk's pose and each foot's path are **guides** (:mod:`hexapod.scene.laws.guided`) and every
actuated joint follows them, so the engine's Newton solve places the legs and the joints carry
the efforts; each foot in stance is a contact whose ground force the scene's policy shares.

**Gaits** (:data:`~legs.patterns.PATTERNS`): each foot lifts off at a fraction of the period
(its phase) and is on the ground for the fraction ``duty`` before that. Patterns name the feet
by role: on four legs ``LF RF LH RH`` (left/right, fore/hind), on six ``L1 L2 L3 R1 R2 R3``
(front to hind), on two ``L R``; the roles are the robot's feet sorted by their rest positions
(left: ``y > 0``; front first). An explicit phase table names the feet themselves.

**Paths** (:class:`StepPath`), in world axes, walking along ``x`` at the constant speed
``stride / period``: a foot in stance stands still on its foothold; in swing it moves to the
next foothold, ``stride`` ahead, along ``x0 + stride S(u)`` lifted by ``step_height B(u)``, with
``u`` the swing's progress, ``S(u)`` the ninth-degree smooth step and ``B(u) = 1024 u^5 (1 -
u)^5``: it leaves and rejoins the ground with zero velocity and acceleration (and third and
fourth derivatives), C4 in time. Each foothold lies under the foot's rest position (relative to
the trunk) at the middle of its stance, on the ground ``z = 0``; the trunk moves at its rest
height above it, level.
"""

from __future__ import annotations

import fnmatch
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from hexapod.scene import Law
from legs.description import by_pattern, read_robot, rest_angles
from legs.duty import StepPathDuty, duty_parameter
from legs.patterns import PATTERNS
from legs.posing import at_start, posed
from legs.stepping import LIFT_RATES, STEP_RATES, OnSchedule
from legs.swing import stance_progress, swing_schedule


def roles(rest: dict[str, np.ndarray]) -> dict[str, str]:
    """Each foot's role in the patterns (foot name -> role), from the feet's rest positions in
    the trunk's frame: left where ``y > 0``, then front to hind by ``x``. Raises ``ValueError``
    for a number of feet no pattern knows, or sides of unequal numbers of feet."""
    left = sorted((f for f, p in rest.items() if p[1] > 0), key=lambda f: -rest[f][0])
    right = sorted((f for f, p in rest.items() if p[1] <= 0), key=lambda f: -rest[f][0])
    if len(rest) not in PATTERNS or len(left) != len(right):
        raise ValueError(f"the patterns are for 2, 4 or 6 feet, as many on each side (y > 0 on "
                         f"the left); this robot has {len(left)} on the left and {len(right)} "
                         "on the right: give the gait's phases by foot")
    names = {1: ("",), 2: ("F", "H"), 3: ("1", "2", "3")}[len(left)]
    out = {}
    for side, feet in (("L", left), ("R", right)):
        for foot, suffix in zip(feet, names, strict=True):
            out[foot] = side + suffix
    return out


def rise_progress(u, rise: float) -> tuple:
    """How much of a step's ``rise`` a swing has taken at its progress ``u`` (and the first
    two derivatives in ``u``): up a step within the swing's first half, down one within its
    second, along the ninth-degree smooth step, so the foot is over the upper tread's level
    while it passes the edge."""
    u = np.asarray(u, dtype=float)
    w = np.clip(2.0 * u if rise > 0 else 2.0 * u - 1.0, 0.0, 1.0)
    inside = (w > 0.0) & (w < 1.0)
    return tuple(np.where(inside, 2.0**m * p(w), w if m == 0 else 0.0)
                 for m, p in enumerate(STEP_RATES))


@dataclass(frozen=True)
class StepPath(OnSchedule, Law):
    """One world coordinate (m) of a walking foot: standing on its foothold in stance, stepping
    to the next in swing (see the module's notes). The foot lifts off at ``lift_off`` (a
    fraction of the ``period``, s) from ``start`` (the value in the stance that ends then) and
    is on the ground for ``duty`` of the period; each step moves it by ``advance``; ``lift``
    is the swing's height (for the vertical coordinate; 0 otherwise). Steps of the ground:
    from stance ``rises_at[i]`` on (stance ``c`` lasts from the ``c``-th lift-off after
    ``t = 0`` to the next; the stance ending at ``t = lift_off period`` is ``0``), the value is
    raised by ``rises[i]``, taken along the swing before it (:func:`rise_progress`)."""

    start: float = 0.0
    advance: float = 0.0
    lift: float = 0.0
    duty: float = 0.75
    period: float = 1.0
    lift_off: float = 0.0
    rises_at: tuple = ()
    rises: tuple = ()
    kind = "step-path"

    def evaluate(self, t):
        k, u, in_swing = swing_schedule(t, self.duty, self.period, self.lift_off)
        swing = 1.0 - self.duty
        stance = stance_progress(t, self.duty, self.period, self.lift_off)
        bump = [p(u) for p in LIFT_RATES]
        value = self.start + self.advance * stance[0] + self.lift * np.where(in_swing, bump[0],
                                                                               0.0)
        rates = [self.advance * stance[m] + np.where(in_swing, self.lift * bump[m]
                                                     / (swing * self.period) ** m, 0.0)
                 for m in (1, 2)]
        for at, rise in zip(self.rises_at, self.rises, strict=True):
            crossing = in_swing & (k == at - 1.0)
            climb = rise_progress(u, rise)
            value = value + rise * np.where(crossing, climb[0], stance[0] >= at)
            for m in (1, 2):
                rates[m - 1] = rates[m - 1] + rise * np.where(
                    crossing, climb[m] / (swing * self.period) ** m, 0.0)
        return value, rates[0], rates[1]

    def design_parameter(self, key):
        """``gait.step_height``: the swing's height ``lift`` (m), of which the path is linear
        (its derivative: the swing's bump, zero in stance); a path without lift (a
        horizontal coordinate) does not depend on it. ``gait.duty``: the swing stretched
        and the footholds moved (:class:`legs.duty.StepPathDuty`), on a ground without
        steps. ``gait.stride``: the path along the walk is linear in it (the footholds
        ``rest + stride (lift_off - duty / 2 + c)``), on flat ground."""
        if key in ("gait.duty", "gait.stride") and self.rises:
            raise ValueError(f"a foot's path over steps of the ground: its dependence on {key} "
                             "is not derived")
        if key == "gait.duty":
            return duty_parameter(self, key, StepPathDuty(self))
        if key == "gait.stride":
            if self.advance == 0.0:
                return None
            if self.lift != 0.0:
                raise ValueError("a foot's height up a slope: its dependence on the stride is "
                                 "not derived")
            # the footholds advance by the stride, stance 0's centred on its middle's time:
            # start = rest + stride (lift_off - duty / 2), linear in the stride
            return self.advance, replace(self, start=self.lift_off - self.duty / 2,
                                         advance=1.0)
        if key != "gait.step_height" or self.lift == 0.0:
            return None
        return self.lift, replace(self, start=0.0, advance=0.0, lift=1.0, rises_at=(),
                                  rises=())

    def cycle_time(self):  # a foot that steps forward (or up) does not come back
        return self.period if self.advance == 0.0 and not self.rises else None

    def problems(self):
        out = self.schedule_problems()
        if not all(np.isfinite(v) for v in (self.start, self.advance, self.lift,
                                            self.lift_off, *self.rises_at, *self.rises)):
            out.append("start, advance, lift, lift_off, rises_at and rises must be finite")
        if len(self.rises_at) != len(self.rises):
            out.append("rises_at and rises must be as long as each other")
        return out


@dataclass(frozen=True)
class TrunkRise(Law):
    """The trunk's height (m) over a ground that is not flat: ``start + speed t`` (up a plane)
    plus each step's ``rises[i]`` (m), taken along the ninth-degree smooth step over ``width``
    (s) centred on ``times[i]`` (s), when the trunk passes the step."""

    start: float = 0.0
    speed: float = 0.0
    times: tuple = ()
    rises: tuple = ()
    width: float = 1.0
    kind = "trunk-rise"

    def design_parameter(self, key):
        """``gait.stride``: refused up a slope or over steps (the trunk passes them at times
        the speed sets); on flat ground the height does not depend on it."""
        if key == "gait.stride" and (self.speed or self.rises):
            raise ValueError("the trunk's height over a ground that is not flat: its "
                             "dependence on the stride is not derived")
        return None

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        out = [self.start + self.speed * t, np.full_like(t, self.speed), np.zeros_like(t)]
        for at, rise in zip(self.times, self.rises, strict=True):
            u = (t - at) / self.width + 0.5
            inside = (u > 0.0) & (u < 1.0)
            v = np.clip(u, 0.0, 1.0)
            for m, p in enumerate(STEP_RATES):
                out[m] = out[m] + rise * (np.where(inside, p(v), v if m == 0 else 0.0)
                                          / self.width**m)
        return tuple(out)

    def problems(self):
        out = []
        if not (np.isfinite(self.width) and self.width > 0):
            out.append(f"width must be positive, got {self.width}")
        if len(self.times) != len(self.rises):
            out.append("times and rises must be as long as each other")
        return out


def _foot_levels(terrain, x0: float, y: float, stride: float) -> dict:
    """The vertical :class:`StepPath` keys of a foot whose footholds are ``(x0 + c stride, y)``
    on ``terrain``: the ground's height under foothold ``c`` is ``start + advance c`` up the
    plane plus ``rises[i]`` from stance ``rises_at[i]`` on (where the foot crosses a step)."""

    def beyond(edge, c):  # the contacts' own arithmetic: foothold c at or beyond the edge
        return bool(terrain.distance(x0 + c * stride, y) >= edge)

    tan = np.tan(np.radians(terrain.slope))
    d0, step = float(terrain.distance(x0, y)), terrain.direction[0] * stride
    start = tan * d0 + sum(rise for edge, rise in terrain.steps if beyond(edge, 0))
    rises_at, rises = [], []
    for edge, rise in terrain.steps:
        if step == 0.0:
            continue  # walking along the risers: never crossed
        guess = np.ceil((edge - d0) / step)  # the stance it is crossed on, to round-off
        rises_at.append(next(float(c) for c in (guess - 1, guess, guess + 1)
                             if beyond(edge, c) != beyond(edge, c - 1)))
        rises.append(rise if step > 0 else -rise)
    start -= sum(r for at, r in zip(rises_at, rises, strict=True) if at <= 0)
    return {"start": start, "advance": tan * step, "rises_at": tuple(rises_at),
            "rises": tuple(rises)}


def _swing_clearance(terrain, x_law, z_law, y: float):
    """For each step a foot crosses (its paths ``x_law`` and ``z_law``, at ``y``): the step's
    distance along the heading, the time the foot passes over its edge, and the height by
    which it clears the edge (m; negative: it hits the riser)."""
    tan = np.tan(np.radians(terrain.slope))
    out = []
    for at in z_law.rises_at:
        lift_off = (z_law.lift_off + at - 1.0) * z_law.period  # the swing that crosses it
        t = lift_off + np.linspace(0.0, 1.0, 4001) * (1.0 - z_law.duty) * z_law.period
        d = terrain.distance(x_law(t), y)
        for edge, _ in terrain.steps:
            if min(d[0], d[-1]) < edge <= max(d[0], d[-1]):
                when = float(np.interp(edge, d, t) if d[-1] > d[0] else np.interp(
                    -edge, -d, t))
                corner = tan * edge + max(sum(r for e, r in terrain.steps if e < edge),
                                          sum(r for e, r in terrain.steps if e <= edge))
                out.append((edge, when, float(z_law(when)) - corner))
    return out


def robot_scene(description):
    """The walking scene of a robot description (:class:`legs.description.RobotDescription`):
    its URDF (or body scene) with a free trunk, the trunk's pose and each foot's path as
    guides, every revolute and prismatic joint following them (or its foot through the cycle,
    the description's ``coupled`` joints), each foot a contact by the gait's schedule, the
    bodies written where the motion has them at ``t = 0`` (:func:`legs.posing.at_start`). Each
    stance's middle lies under the foot's rest position (moved by the foot's ``offset``) on the
    ground, the trunk at the gait's ``height`` above it (default: its rest height, the feet's
    mean on the ground). On a ground that is not flat (the description's ``[ground]`` slope
    and steps) each foothold lies on it, and the trunk keeps its height above the plane, rising
    over each step as it passes. A gait with a yaw rate turns (:mod:`legs.turning`); its pitch
    and roll tilt the trunk.

    Raises
    ------
    ModelError
        The trunk or a foot's link is not a link of the URDF, the URDF's own problems, or a
        swing that would not clear a step's edge.
    """
    from hexapod.scene import GroundForces, Guided, JointDriver, read_urdf

    urdf = (description.body if description.body is not None
            else read_urdf(description.urdf, base="free"))
    trunk = _checked_links(description, urdf)
    angles = rest_angles(description, urdf.joints)
    scene = posed(urdf, angles)
    rest = {name: scene.pose(foot.link).transform_point(foot.point) + np.r_[foot.offset, 0.0]
            for name, foot in description.feet.items()}  # each stance's middle
    height = description.gait.height  # else the feet's mean on the ground:
    height = -float(np.mean([p[2] for p in rest.values()])) if height is None else height
    lifted = posed(urdf, angles, height)
    lifted.ground = GroundForces(**description.ground)
    gait = description.gait
    walk = _Walk(gait, gait.phases or _pattern_phases(gait.pattern, rest),
                 lifted.pose(trunk).position, lifted.ground.terrain, lifted.ground.mu)
    two_feet = _two_feet_phases(description, walk)  # checked before any planning
    plan = _add_trunk(lifted, trunk, walk, rest, height)
    for name in description.feet:
        _add_foot(lifted, description, name, walk, rest[name])
    chains = {name: _leg_joints(urdf, trunk, foot.link)
              for name, foot in description.feet.items()}
    coupled = _coupled_laws(description, chains, walk)
    for joint in urdf.joints.values():
        if joint.drivable:
            lifted.add(JointDriver(f"drive_{joint.name}", joint.name,
                                   coupled.get(joint.name, Guided())))
    for name, chain in chains.items():
        _add_posture(lifted, description, name, [j for j in chain if j not in coupled], angles)
    kinematics = (_whole_body(lifted, trunk, walk, rest, height, plan)
                  if gait.trunk == "whole-body" else None)
    if two_feet:
        _carry(lifted, walk, two_feet, height, kinematics)
    lifted.name, lifted.source = description.name, description.source
    lifted.actuators = description.actuators  # the report checks the motors when there are
    return at_start(lifted)  # written at its motion's start: nothing of the rest pose stays


@dataclass(frozen=True)
class _Walk:
    """A gait's schedule laid on the ground: the feet's lift-off ``phases``, the trunk's
    ``origin`` at ``t = 0``, the ``terrain``; walking along ``x`` at ``speed``, turning about
    ``centre`` at ``rate`` (rad/s) when the gait has a yaw rate."""

    gait: object
    phases: dict
    origin: np.ndarray
    terrain: object
    mu: float

    @property
    def speed(self) -> float:
        return self.gait.stride / self.gait.period

    @property
    def rate(self) -> float:
        return float(np.radians(self.gait.yaw_rate))

    @property
    def centre(self) -> np.ndarray:
        from legs.turning import turn_centre

        return turn_centre(self.origin, self.speed, self.rate)

    def foothold(self, name: str, rest: np.ndarray) -> np.ndarray:
        """The foothold of foot ``name``'s stance 0 (the one ending at its lift-off): its rest
        position where the trunk is at the middle of that stance, on ``z = 0``."""
        from legs.turning import turned

        middle = (self.phases[name] - self.gait.duty / 2) * self.gait.period
        if self.rate:
            return turned(np.r_[rest[:2], 0.0], self.centre, self.rate * middle)
        return np.array([self.straight(name, rest), rest[1], 0.0])

    def straight(self, name: str, rest: np.ndarray) -> float:
        """The ``x`` of foot ``name``'s stance-0 foothold on the straight walk (the one a
        turning walk is planned as)."""
        return rest[0] + self.speed * (self.phases[name] - self.gait.duty / 2) * self.gait.period


def _add_trunk(scene, trunk: str, walk: _Walk, rest: dict, height: float):
    """The trunk's six guides: its sway planned (or level), along ``x`` or round the turn;
    its height over the terrain; its yaw (turning), pitch and roll. Returns the plan."""
    from hexapod.scene import CoordinateDriver, Polynomial
    from legs.trunk_path import TrunkPlan

    gait, terrain, origin = walk.gait, walk.terrain, walk.origin
    plan = TrunkPlan.level(gait.period) if gait.trunk == "level" else _plan(
        walk, rest, height, _masses(scene, trunk))
    starts = {name: walk.foothold(name, p) for name, p in rest.items()}
    rise = _trunk_rise(terrain, origin, walk.speed, starts)
    for axis, law in zip("xyz", (*_sway_laws(walk, plan), rise), strict=True):
        scene.add(CoordinateDriver(f"trunk/{axis}", trunk, axis, law, point=[0.0, 0.0, 0.0],
                                   guide=True))
    yaw = Polynomial((0.0, walk.rate)) if walk.rate else 0.0
    for angle, law in (("roll", np.radians(gait.roll)), ("pitch", np.radians(gait.pitch)),
                       ("yaw", yaw)):
        scene.add(CoordinateDriver(f"trunk/{angle}", trunk, angle, law, guide=True))
    return plan


def _plan(walk: _Walk, rest: dict, height: float, masses: tuple, correction=None):
    """The trunk's sway (:func:`legs.trunk_path.plan_trunk`), planned as a straight walk (a
    turning trunk sways along its own axes, :mod:`legs.turning`); ``correction``: the whole
    body's centre of pressure less the lumped model's, at the plan's samples."""
    from legs.trunk_path import plan_trunk

    gait, terrain, origin = walk.gait, walk.terrain, walk.origin
    period, duty, stride = gait.period, gait.duty, gait.stride
    return plan_trunk(
        {name: (StepPath(walk.straight(name, p), stride, 0.0, duty, period, walk.phases[name]),
                StepPath(0.0, 0.0, gait.step_height, duty, period, walk.phases[name]),
                p[:2] - origin[:2]) for name, p in rest.items()},
        walk.phases, duty, period, stride, height, masses,
        slope=(terrain.slope, terrain.heading), correction=correction, mu=walk.mu)


def _whole_body(scene, trunk: str, walk: _Walk, rest: dict, height: float, plan):
    """The trunk's lumped ``plan`` corrected by the whole robot's centre of pressure
    (:mod:`legs.balance`); returns the guides' kinematics with the corrected laws."""
    from legs.balance import refine_plan
    from legs.turning import straight_frame

    masses = _masses(scene, trunk)
    return refine_plan(
        scene, plan, lambda correction: _plan(walk, rest, height, masses, correction),
        lambda plan: _sway_laws(walk, plan),
        lambda points, t: straight_frame(points, t, walk.centre, walk.rate,
                                         walk.speed) if walk.rate else points)[2]


def _sway_laws(walk: _Walk, plan) -> tuple:
    """The trunk's ``x`` and ``y`` laws of ``plan``: along ``x``, or round the turn."""
    from legs.turning import turning_sway

    if walk.rate:
        return turning_sway(plan, walk.origin, walk.centre, walk.rate)
    return (_sway(plan.x, walk.origin[0], walk.speed, walk.gait.period),
            _sway(plan.y, walk.origin[1], 0.0, walk.gait.period))


def _add_foot(scene, description, name: str, walk: _Walk, rest: np.ndarray) -> None:
    """Foot ``name``'s three guides (its path) and its contact."""
    from hexapod.scene import Contact, CoordinateDriver
    from hexapod.spatial import Placement
    from legs.turning import foot_turn_paths

    gait, foot, terrain = walk.gait, description.feet[name], walk.terrain
    phase, start = walk.phases[name], walk.foothold(name, rest)
    duty, period, stride = gait.duty, gait.period, gait.stride
    vertical = StepPath(lift=gait.step_height, duty=duty, period=period, lift_off=phase,
                        **_foot_levels(terrain, start[0], start[1], stride))
    if walk.rate:
        horizontal = foot_turn_paths(start, walk.centre, walk.rate, duty, period, phase)
    else:
        horizontal = (StepPath(start[0], stride, 0.0, duty, period, phase), start[1])
        _check_clearance(description, name, terrain, horizontal[0], vertical, start[1])
    for axis, law in zip("xyz", (*horizontal, vertical), strict=True):
        scene.add(CoordinateDriver(f"{name}/{axis}", foot.link, axis, law, point=foot.point,
                                   guide=True))
    turning = dict(turn=np.degrees(walk.rate * period), centre=np.r_[walk.centre, 0.0]) if (
        walk.rate) else dict(advance=[stride, 0.0, 0.0])
    scene.add(Contact(f"{name}/ground", "ground", foot.link, child_frame=Placement(foot.point),
                      period=period, duty=duty, lift_off=phase, foothold=start, **turning))


def _coupled_laws(description, chains: dict, walk: _Walk) -> dict:
    """The laws of the joints that follow their foot through the cycle (the description's
    ``coupled``, among each foot's leg joints ``chains``): joint name ->
    :class:`legs.stepping.GaitCoupled` on its foot's schedule."""
    from legs.stepping import GaitCoupled

    gait, out = walk.gait, {}
    for name, chain in chains.items():
        for joint, (follows, amplitude) in by_pattern(description.coupled, chain).items():
            out[joint] = GaitCoupled(amplitude, follows, gait.duty, gait.period,
                                     walk.phases[name])
    return out


def _leg_joints(urdf, trunk: str, link: str) -> list[str]:
    """The drivable joints from the trunk down to ``link``, in that order."""
    parent_joint = {j.child: j for j in urdf.joints.values()}
    chain = []
    while link != trunk and link in parent_joint:
        joint = parent_joint[link]
        if joint.drivable:
            chain.append(joint.name)
        link = joint.parent
    return chain[::-1]


def _add_posture(scene, description, name: str, joints: list[str], angles: dict) -> None:
    """For a leg of more than three joints, the rule that resolves it: the posture nearest
    its rest posture (the description's ``rest``), weighted by ``robot.weights``."""
    from hexapod.scene import PostureDriver

    if len(joints) <= 3:
        return
    weighted = by_pattern(description.weights, joints)
    weights = [weighted.get(joint, 1.0) for joint in joints]
    foot = description.feet[name]
    scene.add(PostureDriver(f"{name}/posture", foot.link, joints,
                            [angles.get(joint, 0.0) for joint in joints], weights,
                            point=foot.point))


def _checked_links(description, urdf) -> str:
    """The trunk's link; raises ``ModelError`` naming every foot link, the trunk or a rest
    angle's pattern that the URDF does not have."""
    from hexapod import ModelError
    from hexapod.scene import Problem

    where = f"robot description {Path(description.source).name}"
    missing = [Problem(where, f"no link '{foot.link}' in {description.urdf.name}",
                       f"{description.source}, robot.feet.{name}")
               for name, foot in description.feet.items() if foot.link not in urdf.bodies]
    trunk = description.trunk or next(b for b in urdf.bodies if b not in {
        j.child for j in urdf.joints.values()})
    if trunk not in urdf.bodies:
        missing.append(Problem(where, f"no link '{trunk}' in {description.urdf.name}",
                               f"{description.source}, robot.trunk"))
    for table in ("rest", "weights"):  # a key that matches no joint is a typing error
        for key in getattr(description, table):
            if not any(fnmatch.fnmatchcase(joint, key) for joint in urdf.joints):
                missing.append(Problem(where, f"matches no joint of {description.urdf.name}",
                                       f"{description.source}, robot.{table}.{key}"))
    if missing:
        raise ModelError(where, missing)
    return trunk


def _trunk_rise(terrain, origin: np.ndarray, speed: float, starts: dict):
    """The trunk's height: its rest height above the plane under it, at the trunk's mean
    speed along ``x``, rising by each step over the time the feet take to pass it."""
    if terrain.flat:
        return float(origin[2])
    tan, d0 = np.tan(np.radians(terrain.slope)), float(terrain.distance(*origin[:2]))
    along = terrain.direction[0] * speed  # the trunk's speed along the heading
    reach = [float(terrain.distance(*p[:2])) for p in starts.values()]
    width = max(max(reach) - min(reach), 1e-3) / abs(along) if along else 1.0
    if not along:  # walking along the risers: on the tread it starts on
        return TrunkRise(origin[2] + float(terrain.height(*origin[:2])), 0.0)
    # from t = -inf (every step ahead, or behind when walking down the heading) on
    start = origin[2] + tan * d0 + (sum(r for _, r in terrain.steps) if along < 0 else 0.0)
    times = tuple((e - d0) / along for e, _ in terrain.steps)
    rises = tuple(r if along > 0 else -r for _, r in terrain.steps)
    return TrunkRise(start, tan * along, times, rises, width)


def _check_clearance(description, name: str, terrain, x_law, z_law, y: float):
    """Raise ``ModelError`` where foot ``name``'s swing would pass a step's edge lower than
    the gait's clearance, naming the foot, the time and the step."""
    from hexapod import ModelError
    from hexapod.scene import Problem

    gait = description.gait
    clearance = gait.step_height / 4 if gait.clearance is None else gait.clearance
    for edge, t, above in _swing_clearance(terrain, x_law, z_law, y):
        if above < clearance:
            where = f"robot description {Path(description.source).name}"
            raise ModelError(where, [Problem(where, (
                f"foot {name}'s swing at t = {t:.3g} s passes the step at {edge:g} m "
                f"{above * 1e3:.3g} mm above its edge, less than the clearance of "
                f"{clearance * 1e3:.3g} mm: raise gait.step_height, or move the step"),
                f"{description.source}, ground.steps")])


def _pattern_phases(pattern: str, rest: dict[str, np.ndarray]) -> dict[str, float]:
    """The lift-off phase of each foot in ``pattern``, by the feet's roles."""
    by_role, _ = PATTERNS[len(rest)][pattern]
    return {foot: by_role[role] for foot, role in roles(rest).items()}


def _masses(scene, trunk: str) -> tuple[float, float]:
    """The trunk's mass and the other bodies' (kg)."""
    total = sum(body.mass for body in scene.bodies.values())
    return scene.bodies[trunk].mass, total - scene.bodies[trunk].mass


def _sway(series: tuple, start: float, speed: float, period: float):
    """The law ``start + speed t`` plus a planned sway ``(offset, cos, sin)`` of ``period``."""
    from legs.carried import TrunkSway

    offset, cos, sin = series
    return TrunkSway(start + offset, speed, cos, sin, period)


def _two_feet_phases(description, walk: _Walk) -> list:
    """The gait's phases with two feet down (:func:`legs.carried.two_feet_phases`); a gait
    with one foot down, or whose pairs hand the robot over in no time, is a ``ModelError``
    naming ``gait.duty``."""
    from hexapod import ModelError
    from hexapod.scene import Problem
    from legs.carried import two_feet_phases

    gait = walk.gait
    try:
        return two_feet_phases(walk.phases, gait.duty, gait.period)
    except ValueError as error:
        where = f"robot description {Path(description.source).name}"
        raise ModelError(where, [Problem(where, str(error),
                                         f"{description.source}, gait.duty")]) from None


def _carry(scene, walk: _Walk, phases: list, height: float, kinematics=None) -> None:
    """Where only two feet are down (a trot, a pace, a bound: ``phases``), the trunk's sway
    corrected so that they can carry it (:mod:`legs.carried`); ``kinematics``: the scene's
    guides' kinematics when it is assembled already (the whole-body plan's)."""
    from dataclasses import replace

    import hexapod as hx
    from legs.carried import carry, free_axis

    feet = {name: tuple(scene.drivers[f"{name}/{axis}"].law for axis in "xyz")
            for name in walk.phases}
    axis = free_axis(phases, feet, walk.rate)
    if walk.rate:  # both world coordinates hold the sway's correction along the trunk's axis
        sways = {name: replace(scene.drivers[name].law, free=axis)
                 for name in ("trunk/x", "trunk/y")}
    else:
        sways = {f"trunk/{'xy'[axis]}": scene.drivers[f"trunk/{'xy'[axis]}"].law}
    weight = sum(body.mass for body in scene.bodies.values()) * float(
        np.linalg.norm(scene.gravity))
    if kinematics is None:
        kinematics = hx.assemble(scene).guidance.kinematics
    for name, law in carry(kinematics, sways, phases, feet, weight * height).items():
        scene.drivers[name].law = law


def robot_from_document(document: dict, path: str | Path):
    """The walking scene of the robot description ``document`` read from ``path`` (the entry
    point ``hexapod.robots``: a scene file with a ``[robot]`` table).

    Raises
    ------
    ModelError
        Every problem of the description, or of its URDF.
    """
    return robot_scene(read_robot(document, path))
