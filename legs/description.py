"""A robot description: a small TOML file beside a URDF that says how the robot walks.

.. code-block:: toml

    [robot]
    name = "quadruped"
    urdf = "quadruped.urdf"          # relative to this file, or { package = ..., path = ... }
    trunk = "trunk"                  # the URDF's root link (a free body)
    rest = { "*_flexion" = 0.6, "*_knee" = -1.2 }   # joint angles (rad), names or patterns
    actuators = "motors.toml"        # optional: the motors' table (docs/report.md)
    weights = { "*_ankle" = 4.0 }    # a leg of more than three joints: the posture nearest
                                     # the rest one, these weights on the joints (default 1)
    coupled = { "*_wrist" = { lift = 8 } }   # or: joints that follow their foot through the
                                     # cycle, degrees at the top of the swing (lift) or at
                                     # touch-down (reach: minus that at lift-off)

    [robot.feet]                     # each foot: a link and a point of it (m, link frame)
    LF = { link = "LF_shank", point = [0.0, 0.0, -0.2] }   # offset = [dx, dy]: the stance's
                                     # middle that far from under the rest foot (m)

    [gait]
    pattern = "walk"                 # or phases = { LF = 0.25, ... } (lift-off fractions)
    duty = 0.75                      # default: the pattern's
    period = 0.8                     # s; or speed (m/s)
    stride = 0.12                    # m, the trunk's advance per period
    step_height = 0.04               # m
    clearance = 0.01                 # m above a step's edge (default: step_height / 4)
    trunk = "planned"                # or "whole-body" (the plan corrected by the whole
                                     # robot's centre of pressure), or "level"
    yaw_rate = 10                    # degrees per second, turning left (flat ground)
    pitch = 0                        # degrees, the trunk's tilt (and roll)
    height = 0.28                    # m, the trunk's frame above the ground (default: where
                                     # the rest posture puts the feet on it)

    [ground]                         # optional: the ground, as in a scene file
    policy = "min-wrench"            # how the feet share the load
    slope = 10                       # degrees, rising along x (heading = 0 degrees)
    steps = [[0.3, 0.03]]            # risers: [at, rise] (m) along the heading

:func:`read_robot` checks everything and lists every problem at once, naming the file and the
key; :func:`legs.walker.robot_scene` builds the walking scene. A scene file whose document has
a ``[robot]`` table is read as a robot description wherever a scene is (``hexapod report
ROBOT.toml``), through the entry point ``hexapod.robots``
(:func:`legs.walker.robot_from_document`).
"""

from __future__ import annotations

import fnmatch
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hexapod import ModelError, Scene
from hexapod.scene import ActuatorTable, GroundForces, Problem, read_actuators
from legs.patterns import PATTERNS

_ROBOT_KEYS = {"name", "urdf", "trunk", "rest", "feet", "actuators", "weights", "coupled"}
_GROUND_KEYS = {"policy", "mu", "faces", "min_normal", "default_reference", "reference_efforts",
                "slope", "heading", "steps"}
_GAIT_KEYS = {"pattern", "phases", "duty", "period", "speed", "stride", "step_height", "trunk",
              "clearance", "yaw_rate", "pitch", "roll", "height"}


@dataclass
class Foot:
    """A foot: the point ``point`` (m) of link ``link``, in the link's frame; the middle of its
    stance lies ``offset`` (m, along the trunk's x and y) from under its rest position."""

    link: str
    point: np.ndarray
    offset: np.ndarray = field(default_factory=lambda: np.zeros(2))


@dataclass
class Gait:
    """How the robot walks: lift-off ``phases`` by foot, ``duty``, ``period`` (s), ``stride``
    (m per period), ``step_height`` (m), and the ``trunk``'s motion: ``planned`` (swaying so
    that the centre of pressure stays inside the support polygon, :mod:`legs.trunk_path`),
    ``whole-body`` (that plan corrected by the whole robot's centre of pressure,
    :mod:`legs.balance`) or ``level`` (straight, at constant speed); a swing that crosses a
    step clears its edge by at least ``clearance`` (m; default a quarter of the step
    height). The trunk turns at ``yaw_rate`` (degrees per second, counter-clockwise seen from
    above; flat ground) and is tilted by ``pitch`` and ``roll`` (degrees); its frame's origin
    is ``height`` (m) above the ground (None: where the rest posture puts the feet on it)."""

    phases: dict[str, float]
    duty: float
    period: float
    stride: float
    step_height: float
    pattern: str = ""
    trunk: str = "planned"
    clearance: float | None = None
    yaw_rate: float = 0.0
    pitch: float = 0.0
    roll: float = 0.0
    height: float | None = None


@dataclass
class RobotDescription:
    """A robot read by :func:`read_robot`: its URDF, trunk, feet, rest posture, gait, ground,
    its motors (an actuator table, :func:`hexapod.scene.read_actuators`), if any, the joints'
    weights in the posture rule of a leg with more than three joints, and the joints that
    follow their foot through the cycle (``coupled``: name or pattern -> ``("lift" or
    "reach", amplitude in rad)``, see :class:`legs.stepping.GaitCoupled`). ``body``: the
    robot's bodies and joints as a scene (a free trunk), in place of the URDF's."""

    name: str
    urdf: Path
    trunk: str
    feet: dict[str, Foot]
    rest: dict[str, float]
    gait: Gait
    ground: dict = field(default_factory=dict)
    source: str = ""
    actuators: ActuatorTable | None = None
    weights: dict[str, float] = field(default_factory=dict)
    coupled: dict[str, tuple[str, float]] = field(default_factory=dict)
    body: Scene | None = None


class _Problems:
    """Problems of one file, each with its key."""

    def __init__(self, path: Path):
        self.path, self.items = path, []

    def add(self, key: str, message: str) -> None:
        self.items.append(Problem(f"robot description {self.path.name}", message,
                                  f"{self.path}, {key}"))

    def number(self, table: dict, key: str, where: str, low=None, high=None, default=None):
        value = table.get(key, default)
        if value is None:
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(
                value):
            self.add(f"{where}.{key}", f"must be a number, got {value!r}")
            return None
        if (low is not None and not value > low) or (high is not None and not value < high):
            self.add(f"{where}.{key}", f"must be in ({low}, {high}), got {value}")
            return None
        return float(value)


def read_robot(document: dict, path: str | Path) -> RobotDescription:
    """The robot description of a parsed TOML ``document`` read from ``path`` (which names it in
    messages; its URDF is found relative to it).

    Raises
    ------
    ModelError
        Every problem of the description: unknown keys, a missing URDF, feet without a link or
        a point of three numbers, a gait that is no pattern for the robot's feet or a phase
        table that forgets a foot, numbers out of range.
    """
    path = Path(path)
    problems = _Problems(path)
    robot = document.get("robot")
    if not isinstance(robot, dict):
        problems.add("robot", "must be a table")
        raise ModelError(f"robot description {path}", problems.items)
    for key in sorted(set(robot) - _ROBOT_KEYS):
        problems.add(f"robot.{key}", f"unknown key (expected {', '.join(sorted(_ROBOT_KEYS))})")
    urdf = _urdf(robot.get("urdf"), path, problems)
    feet = _feet(robot.get("feet"), problems)
    rest = robot.get("rest", {})
    if not isinstance(rest, dict) or not all(isinstance(v, (int, float)) for v in rest.values()):
        problems.add("robot.rest", "must be a table of joint names (or patterns) and angles")
        rest = {}
    weights = robot.get("weights", {})
    if not isinstance(weights, dict) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0
            for v in weights.values()):
        problems.add("robot.weights", "must be a table of joint names (or patterns) and "
                     "positive weights")
        weights = {}
    coupled = _coupled(robot.get("coupled", {}), problems)
    gait = _gait(document.get("gait", {}), list(feet), problems)
    ground = document.get("ground", {})
    if not isinstance(ground, dict):
        problems.add("ground", "must be a table (the ground-force policy, as in a scene file)")
        ground = {}
    for key in sorted(set(ground) - _GROUND_KEYS):
        problems.add(f"ground.{key}", f"unknown key (expected {', '.join(sorted(_GROUND_KEYS))})")
    ground = {key: value for key, value in ground.items() if key in _GROUND_KEYS}
    for problem in GroundForces(**ground, source="ground").problems():  # the walk stands on it
        problems.add(problem.where, problem.message)
    if gait is not None and gait.yaw_rate and any(ground.get(key) for key in ("slope", "steps")):
        problems.add("gait.yaw_rate", "a robot turns on flat ground only, for now: give "
                     "ground.slope and ground.steps or the yaw rate, not both")
    motors = robot.get("actuators")
    if motors is not None and not (isinstance(motors, str) and (path.parent / motors).is_file()):
        problems.add("robot.actuators", f"needs an actuator table file, relative to {path.name} "
                     f"(docs/report.md), got {motors!r}")
    if problems.items:
        raise ModelError(f"robot description {path}", problems.items)
    return RobotDescription(str(robot.get("name", path.stem)), urdf, str(robot.get("trunk", "")),
                            feet, {str(k): float(v) for k, v in rest.items()}, gait, ground,
                            str(path), None if motors is None else read_actuators(
                                (path.parent / motors).resolve()),
                            {str(k): float(v) for k, v in weights.items()}, coupled)


def _urdf(value, path: Path, problems: _Problems) -> Path:
    """The URDF file: relative to the description, or ``{ package = NAME, path = PATH }``, a
    file of an installed distribution (``example-robot-data``'s robots) whose path ends with
    ``PATH``."""
    if isinstance(value, dict) and set(value) == {"package", "path"}:
        from importlib.metadata import PackageNotFoundError, distribution

        try:
            files = distribution(str(value["package"])).files or []
        except PackageNotFoundError:
            problems.add("robot.urdf", f"needs the package '{value['package']}' installed (pip "
                         "install 'hexapod[robots]' for example-robot-data)")
            return Path()
        found = [f for f in files if str(f).replace("\\", "/").endswith(str(value["path"]))]
        if found:
            return Path(found[0].locate())
        problems.add("robot.urdf", f"package '{value['package']}' has no file ending with "
                     f"{value['path']}")
        return Path()
    urdf = path.parent / str(value or "")
    if not isinstance(value, str) or not urdf.is_file():
        problems.add("robot.urdf", f"needs the robot's URDF file, relative to {path.name}, or "
                     "{ package = NAME, path = PATH } of an installed package"
                     + (f": no file {urdf}" if isinstance(value, str) else ""))
    return urdf


def _coupled(table, problems: _Problems) -> dict[str, tuple[str, float]]:
    """``robot.coupled``: joint name or pattern -> ``{ lift = DEG }`` or ``{ reach = DEG }``."""
    out = {}
    for name, law in (table.items() if isinstance(table, dict) else [(None, None)]):
        value = next(iter(law.values())) if isinstance(law, dict) and law else None
        if (not isinstance(law, dict) or len(law) != 1 or next(iter(law)) not in (
                "lift", "reach") or isinstance(value, bool)
                or not isinstance(value, (int, float)) or not np.isfinite(value)):
            problems.add("robot.coupled" + ("" if name is None else f".{name}"),
                         "must be a table of joint names (or patterns) and { lift = DEGREES } "
                         "or { reach = DEGREES }")
            continue
        out[str(name)] = (next(iter(law)), float(np.radians(value)))
    return out


def _feet(table, problems: _Problems) -> dict[str, Foot]:
    if not isinstance(table, dict) or not table:
        problems.add("robot.feet", "must name each foot: FOOT = { link = ..., point = [x, y, "
                     "z] }")
        return {}
    out = {}
    for name, foot in table.items():
        point = foot.get("point", [0.0, 0.0, 0.0]) if isinstance(foot, dict) else None
        offset = foot.get("offset", [0.0, 0.0]) if isinstance(foot, dict) else None
        if (not isinstance(foot, dict) or not isinstance(foot.get("link"), str)
                or not _numbers(point, 3) or not _numbers(offset, 2)
                or set(foot) - {"link", "point", "offset"}):
            problems.add(f"robot.feet.{name}", "needs link = \"LINK\" and point = [x, y, z] "
                         "(m, in the link's frame), and may give offset = [dx, dy] (m)")
            continue
        out[name] = Foot(foot["link"], np.array(point, dtype=float),
                         np.array(offset, dtype=float))
    return out


def _numbers(value, size: int) -> bool:
    return (isinstance(value, list) and len(value) == size and all(
        isinstance(x, (int, float)) and not isinstance(x, bool) and np.isfinite(x)
        for x in value))


def _gait(table, feet: list[str], problems: _Problems) -> Gait | None:
    if not isinstance(table, dict):
        problems.add("gait", "must be a table")
        return None
    for key in sorted(set(table) - _GAIT_KEYS):
        problems.add(f"gait.{key}", f"unknown key (expected {', '.join(sorted(_GAIT_KEYS))})")
    pattern, phases = table.get("pattern"), table.get("phases")
    default_duty = None
    if phases is not None:
        if not isinstance(phases, dict) or set(phases) != set(feet) or not all(
                isinstance(v, (int, float)) and 0 <= v < 1 for v in phases.values()):
            forgotten = sorted(set(feet) - set(phases)) if isinstance(phases, dict) else []
            problems.add("gait.phases", "must give every foot a lift-off fraction in [0, 1)"
                         + (f" (forgets {', '.join(forgotten)})" if forgotten else ""))
            phases = None
    else:
        known = PATTERNS.get(len(feet), {})
        pattern = "walk" if pattern is None and "walk" in known else pattern
        if not known:
            problems.add("gait.pattern", f"no pattern is known for {len(feet)} feet (patterns "
                         "are for 2, 4 or 6): give phases by foot")
        elif pattern not in known:
            problems.add("gait.pattern", f"must be one of {', '.join(known)} for "
                         f"{len(feet)} feet, or give phases by foot; got {pattern!r}")
        else:
            default_duty = known[pattern][1]
    duty = problems.number(table, "duty", "gait", 0.0, 1.0, default_duty)
    stride = problems.number(table, "stride", "gait", 0.0, None, 0.1)
    height = problems.number(table, "step_height", "gait", 0.0, None, 0.03)
    period = problems.number(table, "period", "gait", 0.0)
    speed = problems.number(table, "speed", "gait", 0.0)
    if (period is None) == (speed is None):
        problems.add("gait.period", "give the period (s) or the speed (m/s), one of them")
    elif period is None and stride is not None:
        period = stride / speed
    if duty is None and phases is not None:
        problems.add("gait.duty", "a phase table needs the duty factor")
    trunk = table.get("trunk", "planned")
    if trunk not in ("planned", "whole-body", "level"):
        problems.add("gait.trunk", f"must be 'planned', 'whole-body' or 'level', got {trunk!r}")
    clearance = problems.number(table, "clearance", "gait", 0.0)
    yaw_rate = problems.number(table, "yaw_rate", "gait", default=0.0)
    pitch, roll = (problems.number(table, key, "gait", -45.0, 45.0, 0.0)
                   for key in ("pitch", "roll"))
    trunk_height = problems.number(table, "height", "gait", 0.0)
    if None in (duty, stride, height, period, yaw_rate, pitch, roll):
        return None
    return Gait(dict(phases) if phases else {}, duty, period, stride, height, pattern or "",
                trunk, clearance, yaw_rate, pitch, roll, trunk_height)


def by_pattern(table: dict[str, float], joints) -> dict[str, float]:
    """The value of each of ``joints`` (names) in ``table``: the first entry whose name or
    pattern matches it (joints that none matches are left out)."""
    out = {}
    for joint in joints:
        for key, value in table.items():
            if fnmatch.fnmatchcase(joint, key):
                out[joint] = value
                break
    return out


def rest_angles(description: RobotDescription, joints) -> dict[str, float]:
    """The rest angle of each of ``joints`` (names): the first entry of ``rest`` whose name or
    pattern matches it, else 0 (left out)."""
    return by_pattern(description.rest, joints)
