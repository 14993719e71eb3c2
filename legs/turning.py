"""A robot turning at a constant yaw rate: the trunk on a circle, the footholds on circles.

Walking at the speed ``v = stride / period`` while turning at the yaw rate ``w`` (rad/s,
counter-clockwise seen from above), the trunk's reference point moves on the circle of radius
``R = v / w`` about the centre ``C``, a distance ``R`` to the left of where it starts, and its
yaw is ``w t``: every point carried by the trunk turns about the vertical through ``C``. A
foot's foothold of stance ``c`` is its rest position turned about ``C`` by ``w`` times the
middle of that stance, so the footholds of one foot lie on a circle ``w period`` apart; in
swing the foot moves along that circle from one to the next, by the angle ``w period S(u)``
(``S`` the walker's ninth-degree smooth step): it leaves and rejoins the ground with zero
velocity and acceleration, as on a straight walk (:class:`TurnPath`).

The trunk's planned sway (:mod:`legs.trunk_path`, planned as for a straight walk: the curvature's
own effect on the centre of pressure, the centripetal ``v w`` per unit of mass, is left to the
inverse dynamics, whose friction policy says where a foot would slip) is applied in the trunk's
turning frame (:func:`turning_sway`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hexapod.scene import Law
from legs.carried import TrunkSway, sway_design_parameter
from legs.stepping import OnSchedule
from legs.swing import stance_progress


@dataclass(frozen=True)
class TurnPath(OnSchedule, Law):
    """One horizontal world coordinate (m; ``axis`` 0 for ``x``, 1 for ``y``) of a foot whose
    footholds lie on the circle of ``radius`` about ``(centre_x, centre_y)``: at the angle
    ``angle + c turn`` (rad) in stance ``c``, moving along the circle in swing (see the module's
    notes). The schedule is the foot's: ``duty``, ``period`` (s) and ``lift_off`` (a fraction of
    the period)."""

    centre_x: float = 0.0
    centre_y: float = 0.0
    radius: float = 1.0
    angle: float = 0.0
    turn: float = 0.0
    axis: int = 0
    duty: float = 0.75
    period: float = 1.0
    lift_off: float = 0.0
    kind = "turn-path"

    def evaluate(self, t):
        s, s1, s2 = stance_progress(t, self.duty, self.period, self.lift_off)
        theta, rate, acceleration = self.angle + self.turn * s, self.turn * s1, self.turn * s2
        r = self.radius
        if self.axis == 0:
            c, sn = np.cos(theta), np.sin(theta)
            return (self.centre_x + r * c, -r * sn * rate,
                    -r * c * rate**2 - r * sn * acceleration)
        c, sn = np.cos(theta), np.sin(theta)
        return (self.centre_y + r * sn, r * c * rate, -r * sn * rate**2 + r * c * acceleration)

    def cycle_time(self):  # the footholds go round: periodic only when they do not move
        return self.period if self.turn == 0.0 else None

    def problems(self):
        out = self.schedule_problems()
        if self.axis not in (0, 1):
            out.append(f"axis must be 0 (x) or 1 (y), got {self.axis!r}")
        if not all(np.isfinite(v) for v in (self.centre_x, self.centre_y, self.radius,
                                            self.angle, self.turn, self.lift_off)):
            out.append("centre_x, centre_y, radius, angle, turn and lift_off must be finite")
        return out


def turn_centre(origin, speed: float, rate: float) -> np.ndarray:
    """The centre ``(x, y)`` of the circle of a trunk starting at ``origin`` heading along
    ``x`` at ``speed`` (m/s) and turning at ``rate`` (rad/s): ``speed / rate`` to its left."""
    return np.array([origin[0], origin[1] + speed / rate])


def turned(point, centre, angle):
    """``point`` ``(x, y, ...)`` turned by ``angle`` (rad) about the vertical through
    ``centre``; further components unchanged."""
    point = np.array(point, dtype=float)
    d = point[:2] - centre
    c, s = np.cos(angle), np.sin(angle)
    point[:2] = centre + np.array([c * d[0] - s * d[1], s * d[0] + c * d[1]])
    return point


def foot_turn_paths(foothold, centre, rate: float, duty: float, period: float,
                    lift_off: float) -> tuple[TurnPath, TurnPath]:
    """A foot's ``x`` and ``y`` laws: its foothold of stance 0 is ``foothold``, each next one
    ``rate period`` further round ``centre``."""
    d = np.asarray(foothold[:2], dtype=float) - centre
    keys = dict(centre_x=float(centre[0]), centre_y=float(centre[1]),
                radius=float(np.hypot(*d)), angle=float(np.arctan2(d[1], d[0])),
                turn=rate * period, duty=duty, period=period, lift_off=lift_off)
    return TurnPath(axis=0, **keys), TurnPath(axis=1, **keys)


def turning_sway(plan, origin, centre, rate: float) -> tuple:
    """The trunk's ``x`` and ``y`` laws turning at ``rate`` (rad/s) about ``centre``, with the
    planned sway ``plan`` (:class:`legs.trunk_path.TrunkPlan`) along the trunk's own axes:
    ``C + Rz(rate t) (origin - C + sway(t))`` (:class:`TurnedSway`)."""
    keys = dict(rate=rate, cx=float(centre[0]), cy=float(centre[1]),
                dx=float(origin[0] - centre[0]), dy=float(origin[1] - centre[1]),
                period=plan.period, x0=plan.x[0], xcos=plan.x[1], xsin=plan.x[2],
                y0=plan.y[0], ycos=plan.y[1], ysin=plan.y[2])
    return TurnedSway(axis=0, **keys), TurnedSway(axis=1, **keys)


@dataclass(frozen=True, eq=False)
class TurnedSway(Law):
    """One world coordinate (``axis`` 0: ``x``, 1: ``y``; m) of a trunk turning at ``rate``
    (rad/s) about ``(cx, cy)``: ``C + Rz(rate t) (d + s(t))`` with ``d = (dx, dy)`` its start
    from the centre and ``s`` its sway along its own axes, each the series ``x0, xcos, xsin``
    and ``y0, ycos, ysin`` of ``period`` (s) as :class:`legs.carried.TrunkSway` has them; the
    sway's component ``free`` (0 or 1) takes the correction ``bounds, values`` that lets two
    feet carry it (none when empty)."""

    axis: int = 0
    rate: float = 0.0
    cx: float = 0.0
    cy: float = 0.0
    dx: float = 0.0
    dy: float = 0.0
    period: float = 1.0
    x0: float = 0.0
    xcos: tuple = ()
    xsin: tuple = ()
    y0: float = 0.0
    ycos: tuple = ()
    ysin: tuple = ()
    free: int = 1
    bounds: tuple = ()
    values: tuple = ()
    _sway: object = field(default=None, init=False, repr=False, compare=False)
    kind = "turned-sway"

    def design_parameter(self, key):
        if key == "gait.stride":
            raise ValueError("a turning trunk: its dependence on the stride (the circle's "
                             "radius) is not derived")
        return sway_design_parameter(self.bounds, key, any(self.xcos + self.xsin + self.ycos
                                                           + self.ysin))

    def __post_init__(self):
        for key in ("xcos", "xsin", "ycos", "ysin", "bounds", "values"):
            object.__setattr__(self, key, tuple(float(x) for x in np.ravel(getattr(self, key))))
        # the sway along the trunk's own axes, the correction on its component ``free``
        object.__setattr__(self, "_sway", [
            TrunkSway(start, 0.0, cos, sin, self.period, self.bounds if k == self.free else (),
                      self.values if k == self.free else ())
            for k, (start, cos, sin) in enumerate(((self.x0, self.xcos, self.xsin),
                                                   (self.y0, self.ycos, self.ysin)))])

    def evaluate(self, t):
        t = np.asarray(t, dtype=float)
        (u, u1, u2), (v, v1, v2) = (law.evaluate(t) for law in self._sway)
        a, b = self.dx + u, self.dy + v  # the trunk from the centre, in its own axes
        c, s, w = np.cos(self.rate * t), np.sin(self.rate * t), self.rate
        if self.axis == 0:  # x = cx + c a - s b
            return (self.cx + c * a - s * b,
                    c * (u1 - w * b) - s * (v1 + w * a),
                    c * (u2 - 2 * w * v1 - w * w * a) - s * (v2 + 2 * w * u1 - w * w * b))
        return (self.cy + s * a + c * b,  # y = cy + s a + c b
                s * (u1 - w * b) + c * (v1 + w * a),
                s * (u2 - 2 * w * v1 - w * w * a) + c * (v2 + 2 * w * u1 - w * w * b))

    def problems(self):
        out = []
        if self.axis not in (0, 1) or self.free not in (0, 1):
            out.append(f"axis and free must be 0 or 1, got {self.axis!r} and {self.free!r}")
        if not all(np.isfinite(v) for v in (self.rate, self.cx, self.cy, self.dx, self.dy)):
            out.append("rate, cx, cy, dx and dy must be finite")
        for sway in self._sway:
            out += sway.problems()
        return list(dict.fromkeys(out))


def straight_frame(points, t, centre, rate: float, speed: float) -> np.ndarray:
    """World points ``x, y`` (N, 2) at times ``t`` (N,) in the frame of the straight walk
    the turn is planned as (:func:`turning_sway`, whose map is ``W = C + Rz(rate t) (P -
    (speed t, 0) - C)``): turned back about the centre ``C`` by ``rate t``, the trunk's
    advance ``speed t`` along ``x`` added."""
    d = np.asarray(points, dtype=float) - centre
    c, s = np.cos(rate * t), np.sin(rate * t)
    back = np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])
    return back + centre + np.column_stack([speed * t, np.zeros_like(t)])
