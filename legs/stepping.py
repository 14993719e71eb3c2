"""Foot paths of a walking leg, and the joint laws that make the foot follow them.

Seen from the trunk, which moves forward at a constant speed, a foot in **stance** stays on the
ground: it moves backwards along a straight line parallel to the body's axis, at the walking
speed, over ``STANCE_LENGTH_MM`` in the stance time (the duty factor of the period). In
**swing** it returns forwards, lifted by up to ``FOOT_LIFT_MM``. The swing's fore-aft motion
leaves and rejoins the stance line with the stance's velocity and zero second to fourth
derivatives (a ninth-degree smooth step: the foot reverses smoothly, overshooting the line's
ends a little); its lift is ``1024 u^5 (1 - u)^5`` of the swing's progress ``u``. The path is
C4. Every leg walks on the same ground at the same speed, so the feet in stance do not slip
against each other, whatever the gait.

The joints: ``thc_levation`` and ``coxa_rotation`` rise and fall with the foot's lift, ``tita``
follows its fore-aft position (:class:`GaitCoupled`, closed forms of the path, with the
amplitudes of ``legs.cockroach.GAIT_LAWS``); ``thc_protraction``, ``ctr`` and ``fti`` follow the
foot's path: the path is a guide (:class:`FootPath`) and the engine's own kinematics places the
leg (:mod:`hexapod.scene.laws.guided`); the project has no inverse kinematics of its own.
:func:`leg_motion` gives the angles along a cycle. For the scenes whose joints take plain
periodic laws (the robot on a bench, the leg of Dumitru, Marin and Margine's figures) each
joint's angle is fitted by least squares with ``HARMONICS`` harmonics
(:class:`hexapod.scene.Harmonic`, C-infinity), the coupled ones first so that the solved ones
compensate exactly what the fit makes of them (:func:`stepping_harmonics`).
``scripts/studies/gait_paths.py`` measures how closely the feet then follow their paths. Angles
do not depend on the scale, so the fit is done once per leg position, duty factor and segment
lengths, at natural scale, and serves both sides (the right leg's axes mirror the left's, see
:mod:`legs.leg`).

**Segment lengths** (``lengths``: factors of the coxa, femur, tibia and tarsus lengths, see
:func:`legs.leg.leg_geometry`): the foot path keeps its definition in terms of the rest pose of
the leg *with the new lengths*: the stance line lies ``STANCE_OFFSET_MM`` fore-aft of the new
rest pose's foot, at its lateral distance, on the same ground (``GROUND_Z_MM`` below the
trunk's centre of mass), with the same stride length and lift. A leg whose lengths cannot reach
that path raises ``ValueError`` naming the leg and the factors.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

import hexapod as hx
from hexapod import Scene
from hexapod.scene import Harmonic, Law, cycle_breaks
from legs.cockroach import (
    FOOT_LIFT_MM,
    GAIT_LAWS,
    GROUND_Z_MM,
    STANCE_LENGTH_MM,
    STANCE_OFFSET_MM,
    THC_POINT_MM,
)
from legs.duty import GaitCoupledDuty, duty_parameter
from legs.leg import (
    JOINTS,
    SEGMENT_NAMES,
    LegGeometry,
    describe_lengths,
    leg_geometry,
    length_factors,
)
from legs.swing import LIFT_RATES, STEP_RATES

#: The joints the foot's path places (protraction swings the leg, CTr and FTi set its reach and
#: height), found by the engine's kinematics; the others follow the foot through the cycle.
SOLVED_JOINTS = ("thc_protraction", "ctr", "fti")
COUPLED_JOINTS = {"thc_levation": "lift", "coxa_rotation": "lift", "tita": "reach"}
HARMONICS = 64
SAMPLES = 720  # over one cycle, for the fit


def _smooth_step(u):
    """0 to 1 on [0, 1] with zero first to fourth derivatives at both ends."""
    return u**5 * (126 - 420 * u + 540 * u**2 - 315 * u**3 + 70 * u**4)


def foot_path(tau, duty: float, length: float, lift: float) -> tuple[np.ndarray, np.ndarray]:
    """The foot's fore-aft position from the stance line's middle and its height above the
    ground, at cycle fractions ``tau`` (0 at lift-off; swing until ``1 - duty``)."""
    tau = np.asarray(tau, dtype=float) % 1.0
    swing_share = 1.0 - duty
    fore_aft, height = np.empty_like(tau), np.zeros_like(tau)
    stance = tau >= swing_share
    fore_aft[stance] = length / 2 - length * (tau[stance] - swing_share) / duty
    u = tau[~stance] / swing_share
    rate = -length * swing_share / duty  # the stance velocity, per unit of swing progress
    fore_aft[~stance] = -length / 2 + rate * u + (length - rate) * _smooth_step(u)
    height[~stance] = lift * 1024 * u**5 * (1 - u) ** 5
    return fore_aft, height


@cache
def _unit_geometry(position: str, lengths: tuple[float, float, float, float]) -> LegGeometry:
    """The left ``position`` leg at natural scale (built once: the laws ask at every call)."""
    return leg_geometry(position, "L", scale=1.0, lengths=lengths)


def _leg_label(geometry: LegGeometry) -> str:
    """``"front leg"``, with its length factors when they are not all 1."""
    if all(f == 1.0 for f in geometry.length_factors):
        return f"{geometry.leg} leg"
    return f"{geometry.leg} leg ({describe_lengths(geometry.length_factors)})"


def _fourier_basis(tau: np.ndarray, harmonics: int) -> np.ndarray:
    """Columns 1, cos(2 pi k tau), sin(2 pi k tau) for k = 1 ... ``harmonics``."""
    k = np.arange(1, harmonics + 1)
    x = 2 * np.pi * tau
    return np.hstack([np.ones((tau.size, 1)), np.cos(np.outer(x, k)), np.sin(np.outer(x, k))])


def path_targets(position: str, tau: np.ndarray, duty: float,
                 scale: float = 1.0, lengths=None) -> np.ndarray:
    """Where the foot of a left ``position`` leg should be at cycle fractions ``tau``, in the
    leg's frame (m at ``scale``; the right leg's is the mirror image, y negated): the stance
    line from the rest pose of the leg with its segment ``lengths`` (see the module's notes)."""
    geometry = (_unit_geometry(position, length_factors(lengths)) if scale == 1.0 else
                leg_geometry(position, "L", scale, lengths))
    mm = 1e-3 * scale
    fore_aft, height = foot_path(tau, duty, STANCE_LENGTH_MM * mm, FOOT_LIFT_MM * mm)
    rest_foot = geometry.points[6]
    ground = (GROUND_Z_MM - THC_POINT_MM[position][2]) * mm
    return np.column_stack([rest_foot[0] + STANCE_OFFSET_MM[position] * mm + fore_aft,
                            np.full_like(fore_aft, rest_foot[1]), ground + height])


def stepping_harmonics(position: str, duty: float, harmonics: int = HARMONICS,
                       lengths=None) -> dict[str, tuple]:
    """The harmonics ``(offset, cos, sin)`` in the cycle fraction (0 at lift-off) of every joint
    of a ``front``, ``middle`` or ``hind`` leg walking with ``duty``, its segments' lengths
    multiplied by ``lengths`` (coxa, femur, tibia, tarsus; None: all 1), such that the foot
    follows :func:`foot_path`. Computed once per leg, duty, harmonics and length factors
    (``stepping_harmonics.cache_clear()`` forgets them).

    Raises
    ------
    ValueError
        The leg cannot reach its path (the message names the leg and the factors).
    """
    return _stepping_harmonics(position, duty, harmonics, length_factors(lengths))


@cache
def _stepping_harmonics(position: str, duty: float, harmonics: int,
                        lengths: tuple[float, float, float, float]) -> dict[str, tuple]:
    tau = np.arange(SAMPLES) / SAMPLES
    basis = _fourier_basis(tau, harmonics)
    coefficients = {}
    for joint, law in coupled_laws(duty).items():  # fitted first: the solved ones compensate
        coefficients[joint] = np.linalg.lstsq(basis, law(tau), rcond=None)[0]
    fitted = {joint: Harmonic(c[0], tuple(c[1:harmonics + 1]), tuple(c[harmonics + 1:]))
              for joint, c in coefficients.items()}
    angles = leg_motion(position, duty, tau, lengths, fitted)[0]
    solved = [JOINTS.index(j) for j in SOLVED_JOINTS]
    fit = np.linalg.lstsq(basis, angles[:, solved], rcond=None)[0]
    coefficients.update({joint: fit[:, k] for k, joint in enumerate(SOLVED_JOINTS)})
    return {joint: (float(c[0]), tuple(c[1:harmonics + 1].tolist()),
                    tuple(c[harmonics + 1:].tolist()))
            for joint, c in ((j, coefficients[j]) for j in JOINTS)}


stepping_harmonics.cache_clear = _stepping_harmonics.cache_clear


# ------------------------------------------------------------------ the exact gait

#: the swing's shapes' coefficients (:mod:`legs.swing`), highest power first and padded with
#: zeros to one length, for Horner's rule on all six at once: the same operations, in the same
#: order, as each polynomial's own evaluation (a leading zero adds exactly nothing), at a tenth
#: of its cost
_SHAPES = np.array([np.pad(p.coef[::-1], (LIFT_RATES[0].coef.size - p.coef.size, 0))
                    for p in STEP_RATES + LIFT_RATES])


def _shapes(u: np.ndarray) -> np.ndarray:
    """:data:`STEP_RATES` and :data:`LIFT_RATES` at ``u``: (6, *u.shape)."""
    u = np.asarray(u, dtype=float)
    column = (slice(None),) + (None,) * u.ndim
    y = np.zeros((6,) + u.shape)
    for c in _SHAPES.T:  # in place: a batch of times makes these arrays large
        y *= u
        y += c[column]
    return y


def foot_path_rates(tau, duty: float, length: float, lift: float):
    """:func:`foot_path` and its first and second derivatives in the cycle fraction ``tau``:
    ``(fore_aft, height)`` each as a tuple (value, d/dtau, d2/dtau2)."""
    tau = np.asarray(tau, dtype=float) % 1.0
    a = 1.0 - duty
    stance = tau >= a
    u = np.where(stance, 0.0, tau / a)
    rate = -length * a / duty
    shapes = _shapes(u)
    step, bump = shapes[:3], shapes[3:]
    fore_aft = (
        np.where(stance, length / 2 - length * (tau - a) / duty,
                 -length / 2 + rate * u + (length - rate) * step[0]),
        np.where(stance, -length / duty, (rate + (length - rate) * step[1]) / a),
        np.where(stance, 0.0, (length - rate) * step[2] / a**2),
    )
    height = tuple(np.where(stance, 0.0, lift * b / a**m) for m, b in enumerate(bump))
    return fore_aft, height


def coupled_laws(duty: float, period: float = 1.0, lift_off: float = 0.0) -> dict:
    """The laws of the joints that follow their foot through the cycle (``thc_levation`` and
    ``coxa_rotation`` its lift, ``tita`` its reach), with the amplitudes of
    ``legs.cockroach.GAIT_LAWS``: joint name -> :class:`GaitCoupled`."""
    amplitude = {joint: np.radians(a) for joint, a, _ in GAIT_LAWS}
    return {joint: GaitCoupled(float(amplitude[joint]), follows, duty, period, lift_off)
            for joint, follows in COUPLED_JOINTS.items()}


def guided_leg(position: str, duty: float, lengths=None, laws: dict | None = None, *,
               side: str = "L", scale: float = 1.0, period: float = 1.0,
               lift_off: float = 0.0, name: str | None = None) -> Scene:
    """A walking ``position`` leg hanging from the ground at its thorax-coxa point (the leg's
    frame, :func:`legs.leg.leg_scene`): the joints of :data:`COUPLED_JOINTS` driven by ``laws``
    (joint name -> law; default :func:`coupled_laws`), the others following the foot's path
    (three guides in the leg's frame, :class:`FootPath`), placed by the engine's kinematics
    (:mod:`hexapod.scene.laws.guided`)."""
    from hexapod.scene import CoordinateDriver, Guided
    from legs.leg import leg_scene

    spec = leg_spec(position, lengths)
    driven = dict(laws or coupled_laws(duty, period, lift_off))
    driven.update({joint: Guided() for joint in SOLVED_JOINTS})
    scene = leg_scene(position, side, scale, {joint: driven[joint] for joint in JOINTS}, name,
                      lengths)
    for axis in range(3):
        scene.add(CoordinateDriver(
            f"foot_{'xyz'[axis]}", "tarsus", "xyz"[axis],
            FootPath(spec, side, axis, duty, period, lift_off, scale, base="leg"),
            point="foot", guide=True))
    return scene


def leg_motion(position: str, duty: float, tau, lengths=None,
               laws: dict | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The joint angles (n, 6) of a left ``position`` leg walking with ``duty``, at the
    cycle fractions ``tau`` in [0, 1), and their first and second derivatives in ``tau``, with
    the foot on its path: the laws of :func:`guided_leg` (a period of 1 s), its guides'
    kinematics solved by the engine from the rest pose and along the samples. ``laws``:
    the coupled joints' laws (default :func:`coupled_laws`).

    Raises
    ------
    ValueError
        The leg cannot follow its path (the message names the leg, its length factors, and
        where the engine found the path out of reach).
    """
    tau = np.atleast_1d(np.asarray(tau, dtype=float))
    model = hx.assemble(guided_leg(position, duty, lengths, laws))
    try:
        values = model.law_values(tau)  # the guided joints': the guides' kinematics solved
    except hx.AssemblyError as error:
        label = _leg_label(_unit_geometry(position, length_factors(lengths)))
        raise ValueError(f"{label}: the foot cannot follow its path (the times are fractions "
                         f"of its cycle: {error})") from None
    index = {model.joints[d.joint].name: d.law for d in model.drivers if d.kind == "joint"}
    return tuple(np.column_stack([values[m][index[joint]] for joint in JOINTS])
                 for m in range(3))


def leg_spec(position: str, lengths=None) -> str:
    """The ``position`` of a :class:`Stepping` law: the leg (``front``, ``middle`` or
    ``hind``), followed by those of its length factors that are not 1, as
    ``"front femur_length=1.2 tibia_length=0.9"`` (just ``"front"`` for the cockroach's
    proportions)."""
    return " ".join([position] + [f"{name}_length={factor!r}" for name, factor in
                                  zip(SEGMENT_NAMES, length_factors(lengths), strict=True)
                                  if factor != 1.0])


def parse_leg(spec: str) -> tuple[str, tuple[float, float, float, float]]:
    """``"front femur_length=1.2"`` -> ``("front", (1.0, 1.2, 1.0, 1.0))``: the inverse of
    :func:`leg_spec`.

    Raises
    ------
    ValueError
        Not a leg, or a malformed, unknown, repeated or non-positive factor.
    """
    words = str(spec).split()
    if not words or words[0] not in ("front", "middle", "hind"):
        raise ValueError(f"position must be front, middle or hind (then length factors such as "
                         f"femur_length=1.2), got {spec!r}")
    factors = dict.fromkeys(SEGMENT_NAMES, 1.0)
    seen = set()
    for word in words[1:]:
        key, _, value = word.partition("=")
        name = key.removesuffix("_length")
        if not key.endswith("_length") or name not in factors or name in seen:
            raise ValueError(f"position {spec!r}: {word!r} is not one of "
                             f"{', '.join(n + '_length=<factor>' for n in SEGMENT_NAMES)} "
                             "(each at most once)")
        try:
            factors[name] = float(value)
        except ValueError:
            raise ValueError(f"position {spec!r}: {key} must be a number, got {value!r}") \
                from None
        seen.add(name)
    return words[0], length_factors(tuple(factors.values()))


class OnSchedule:
    """What the laws of a walking foot's schedule share (``period``, s; ``duty`` and
    ``lift_off``, fractions of it): they repeat every period and change regime at lift-off and
    touch-down, where the path's pieces join."""

    def cycle_time(self):
        return self.period

    def breaks(self, start, stop):
        return cycle_breaks(self.period, (self.lift_off, self.lift_off + 1.0 - self.duty),
                            start, stop)

    def design_parameter(self, key):
        """``gait.duty`` and ``gait.stride``: refused unless the law derives them (its path
        changes with them)."""
        if key in ("gait.duty", "gait.stride"):
            raise ValueError(f"a {self.kind} law's dependence on {key} is not derived (a "
                             "walking robot's feet's paths and coupled joints are, on a "
                             "straight walk)")
        return None

    def schedule_problems(self, lowest_duty: float = 0.0) -> list[str]:
        """What is wrong with the schedule: a period that is not positive, a duty outside
        ``(lowest_duty, 1)`` (``[lowest_duty, 1)`` when it is not 0)."""
        out = []
        if not (np.isfinite(self.period) and self.period > 0):
            out.append(f"period must be positive, got {self.period}")
        inside = lowest_duty < self.duty < 1 if lowest_duty == 0.0 else (
            lowest_duty <= self.duty < 1)
        if not inside:
            bracket = "(" if lowest_duty == 0.0 else "["
            out.append(f"duty must be in {bracket}{lowest_duty:g}, 1), got {self.duty}")
        return out


def _position_problems(position: str) -> list[str]:
    """What is wrong with a leg's ``position`` (:func:`parse_leg`), as a list."""
    try:
        parse_leg(position)
    except ValueError as error:
        return [str(error)]
    return []


@dataclass(frozen=True)
class GaitCoupled(OnSchedule, Law):
    """A joint angle (rad) that follows its foot through the gait's cycle: ``amplitude`` times
    the foot's lift over the step height (``follows = "lift"``: 0 in stance, 1 at the top of
    the swing), or times its reach (``"reach"``: the foot's fore-aft position relative to a
    trunk walking straight at constant speed, from the middle of its stance over half the
    stance's length: 1 at touch-down, -1 at lift-off), on the foot's schedule (``duty``,
    ``period`` in s, ``lift_off`` a fraction of it). Closed forms of :func:`foot_path_rates`,
    so as smooth as the path (C4)."""

    amplitude: float = 0.0
    follows: str = "lift"
    duty: float = 0.5
    period: float = 1.0
    lift_off: float = 0.0
    kind = "gait-coupled"

    def evaluate(self, t):
        value, rate, acceleration = type(self).evaluate_batch([self], t)[:, 0]
        return value, rate, acceleration

    def batch_key(self):
        return ("gait-coupled", self.duty, self.period)

    def design_parameter(self, key):
        """``gait.duty`` (:class:`legs.duty.GaitCoupledDuty`)."""
        return duty_parameter(self, key, GaitCoupledDuty(self))

    @classmethod
    def evaluate_batch(cls, laws, t):
        """The laws of one schedule shape (duty, period) in one pass over the foot's path (a
        simulation asks for the robot's 18 of them at every stage: one by one, they took half
        of its steps' time); :meth:`evaluate` is this for one law."""
        t = np.asarray(t, dtype=float)
        shape = (len(laws),) + (1,) * t.ndim
        first = laws[0]
        lift_off, amplitude = (np.array([getattr(law, name) for law in laws]).reshape(shape)
                               for name in ("lift_off", "amplitude"))
        lifts = np.array([law.follows == "lift" for law in laws]).reshape(shape)
        tau = (t[None] / first.period - lift_off) % 1.0
        fore_aft, height = foot_path_rates(tau, first.duty, 1.0, 1.0)
        return np.array([amplitude * np.where(lifts, h, 2.0 * f) / first.period**m
                         for m, (f, h) in enumerate(zip(fore_aft, height, strict=True))])

    def problems(self):
        out = []
        if self.follows not in ("lift", "reach"):
            out.append(f"follows must be 'lift' or 'reach', got {self.follows!r}")
        if not np.isfinite(self.amplitude):
            out.append(f"amplitude must be a finite angle (rad), got {self.amplitude}")
        if not np.isfinite(self.lift_off):
            out.append(f"lift_off must be a finite fraction of the period, got {self.lift_off}")
        return out + self.schedule_problems()


@dataclass(frozen=True)
class FootPath(OnSchedule, Law):
    """One coordinate (m) of a walking leg's foot on its path (:func:`path_targets`): a
    guide's law, so that the engine places the leg's joints (:mod:`hexapod.scene.laws.guided`).
    ``base`` ``trunk``: in the trunk's frame of :func:`legs.robot.hexapod_scene` (from the
    trunk's origin: the leg's thorax-coxa point plus the path, mirrored on the right); ``leg``:
    in the leg's own frame (from its thorax-coxa point, :func:`legs.leg.leg_scene`).
    ``position`` names the leg and its length factors (:func:`leg_spec`: ``"front
    femur_length=1.2"``); ``side`` ``L`` or ``R``; ``axis`` 0, 1, 2 (x forward, y left, z up);
    the gait's ``duty``, ``period`` (s) and the leg's ``lift_off`` (a fraction of the period);
    ``scale`` the robot's."""

    position: str = "front"
    side: str = "L"
    axis: int = 0
    duty: float = 0.5
    period: float = 1.0
    lift_off: float = 0.0
    scale: float = 1.0
    base: str = "trunk"
    kind = "foot-path"

    def evaluate(self, t):
        from legs.cockroach import THC_POINT_MM

        t = np.asarray(t, dtype=float)
        tau = (np.atleast_1d(t) / self.period - self.lift_off) % 1.0
        leg, lengths = parse_leg(self.position)
        sign = -1.0 if (self.side == "R" and self.axis == 1) else 1.0
        origin = 1e-3 * THC_POINT_MM[leg][self.axis] if self.base == "trunk" else 0.0
        # the path is linear in the scale: drawn at natural scale, where its geometry is kept
        value = (path_targets(leg, tau, self.duty, 1.0, lengths)[:, self.axis]
                 + origin) * sign * self.scale
        length, lift = (1e-3 * self.scale * x for x in (STANCE_LENGTH_MM, FOOT_LIFT_MM))
        (_, fa1, fa2), (_, h1, h2) = foot_path_rates(tau, self.duty, length, lift)
        rate, acceleration = {0: (fa1, fa2), 1: (0 * tau, 0 * tau), 2: (h1, h2)}[self.axis]
        return (value.reshape(t.shape), (rate / self.period).reshape(t.shape),
                (acceleration / self.period**2).reshape(t.shape))

    def problems(self):
        out = _position_problems(self.position)
        if self.side not in ("L", "R") or self.axis not in (0, 1, 2):
            out.append(f"side must be L or R and axis 0, 1 or 2, got {self.side!r}, "
                       f"{self.axis!r}")
        for name in ("period", "scale"):
            if not (np.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                out.append(f"{name} must be positive, got {getattr(self, name)}")
        if not 0 < self.duty < 1:
            out.append(f"duty must be in (0, 1), got {self.duty}")
        if self.base not in ("trunk", "leg"):
            out.append(f"base must be 'trunk' or 'leg', got {self.base!r}")
        return out
