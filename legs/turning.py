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

from dataclasses import dataclass

import numpy as np

from hexapod.scene import Law
from legs.stepping import STEP_RATES, OnSchedule


def swing_schedule(t, duty: float, period: float, lift_off: float) -> tuple:
    """A foot's cycle at ``t``: the index ``k`` of the cycle from a lift-off (stance ``k + 1``
    follows the swing of cycle ``k``; stance 0 ends at ``t = lift_off period``), the swing's
    progress ``u`` (0 to 1; 1 in stance) and whether the foot is in swing."""
    x = np.asarray(t, dtype=float) / period - lift_off
    k = np.floor(x)
    tau = x - k  # 0 at lift-off; swing until 1 - duty
    return k, np.clip(tau / (1.0 - duty), 0.0, 1.0), tau < 1.0 - duty


def stance_progress(t, duty: float, period: float, lift_off: float) -> tuple:
    """How many steps a foot has taken at ``t`` and the first two rates (1/s, 1/s^2): ``c``
    in stance ``c``, rising from ``c`` to ``c + 1`` along the smooth step over the swing
    between them."""
    k, u, in_swing = swing_schedule(t, duty, period, lift_off)
    step = [p(u) for p in STEP_RATES]
    value = k + np.where(in_swing, step[0], 1.0)
    swing = (1.0 - duty) * period
    return (value, *(np.where(in_swing, step[m] / swing**m, 0.0) for m in (1, 2)))


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


def turning_sway(plan, origin, centre, rate: float):
    """The trunk's ``x`` and ``y`` laws turning at ``rate`` (rad/s) about ``centre``, with the
    planned sway ``plan`` (:class:`legs.trunk_path.TrunkPlan`) along the trunk's own axes:
    ``C + Rz(rate t) (origin - C + sway(t))``, exact derivatives (expressions)."""
    from hexapod.scene import Expression

    constants = {"w": rate, "cx": float(centre[0]), "cy": float(centre[1]),
                 "dx": float(origin[0] - centre[0]), "dy": float(origin[1] - centre[1]),
                 "f": 2 * np.pi / plan.period}
    sway = []
    for axis, (offset, cos, sin) in zip("xy", (plan.x, plan.y), strict=True):
        constants[f"{axis}0"] = offset
        terms = [f"{axis}0"]
        for k, (a, b) in enumerate(zip(cos, sin, strict=True), 1):
            constants.update({f"{axis}a{k}": a, f"{axis}b{k}": b})
            terms.append(f"{axis}a{k} * cos({k} * f * t) + {axis}b{k} * sin({k} * f * t)")
        sway.append(" + ".join(terms))
    x = f"cx + cos(w * t) * (dx + {sway[0]}) - sin(w * t) * (dy + {sway[1]})"
    y = f"cy + sin(w * t) * (dx + {sway[0]}) + cos(w * t) * (dy + {sway[1]})"
    pairs = tuple(constants.items())
    return Expression(x, pairs), Expression(y, pairs)


def straight_frame(points, t, centre, rate: float, speed: float) -> np.ndarray:
    """World points ``x, y`` (N, 2) at times ``t`` (N,) in the frame of the straight walk
    the turn is planned as (:func:`turning_sway`, whose map is ``W = C + Rz(rate t) (P -
    (speed t, 0) - C)``): turned back about the centre ``C`` by ``rate t``, the trunk's
    advance ``speed t`` along ``x`` added."""
    d = np.asarray(points, dtype=float) - centre
    c, s = np.cos(rate * t), np.sin(rate * t)
    back = np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])
    return back + centre + np.column_stack([speed * t, np.zeros_like(t)])
