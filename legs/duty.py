"""How a walking foot's laws change with the gait's duty factor: the derivative laws behind
the design parameter ``gait.duty`` (:meth:`hexapod.scene.Law.design_parameter`).

The duty factor ``d`` moves a foot's touch-down, its lift-off kept: at a time ``t`` whose
cycle fraction from lift-off is ``tau``, the swing's progress is ``u = tau / a`` with
``a = 1 - d``. A path made of a shape ``f(u)`` over the swing has the ``m``-th time
derivative ``f^(m)(u) / (a T)^m`` (``T`` the period); at a fixed time it changes with ``d`` by

    d/dd [f^(m)(u) / (a T)^m] = (u f^(m+1)(u) + m f^(m)(u)) / (a (a T)^m)

(``u`` grows by ``u / a`` per unit of ``d``, the swing's time ``a T`` shrinks by ``T``): the
derivative of a law is a law again, whose rate is the derivative of its value. Stance pieces
change as their closed forms say. The stride and period are kept (so the speed), and the
footholds stay where the walking builders put them, the middle of each stance under the
foot's rest position: a longer stance starts earlier, and each foothold moves back by half
the stride per unit of duty (``-advance / 2``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod.scene import Law
from legs.swing import LIFT_JERK, LIFT_RATES, STEP_JERK, STEP_RATES, swing_schedule

#: The swing's unit shapes (:mod:`legs.swing`) and the progress itself, each with its first
#: three derivatives.
_SHAPES = {"step": (*STEP_RATES, STEP_JERK), "lift": (*LIFT_RATES, LIFT_JERK),
           "progress": tuple(np.polynomial.Polynomial([0.0, 1.0]).deriv(m) for m in range(4))}


def _cycle(t, duty: float, period: float, lift_off: float) -> tuple:
    """``(tau, u, in_swing)`` at ``t``: the cycle fraction from lift-off, and the swing's
    progress and whether the foot is in swing (:func:`legs.swing.swing_schedule`)."""
    k, u, in_swing = swing_schedule(t, duty, period, lift_off)
    return np.asarray(t, dtype=float) / period - lift_off - k, u, in_swing


def shape_rates(shape: str, u, duty: float, period: float) -> np.ndarray:
    """The derivative with respect to the duty factor, at fixed time, of the swing path
    ``f^(m)(u) / (a T)^m`` of the unit ``shape`` (``step``, ``lift`` or ``progress``), for
    ``m = 0, 1, 2``: (3, *u.shape)."""
    a, f = 1.0 - duty, [p(u) for p in _SHAPES[shape]]
    return np.array([(u * f[m + 1] + m * f[m]) / (a * (a * period) ** m) for m in range(3)])


def shape_values(shape: str, u, duty: float, period: float) -> np.ndarray:
    """The swing path ``f^(m)(u) / (a T)^m`` itself, ``m = 0, 1, 2``: (3, *u.shape)."""
    a = 1.0 - duty
    return np.array([p(u) / (a * period) ** m for m, p in enumerate(_SHAPES[shape][:3])])


@dataclass(frozen=True, eq=False)
class StepPathDuty(Law):
    """The derivative of a :class:`legs.walker.StepPath` (``path``, without steps of the
    ground) with respect to the duty factor: its swing's fore-aft step and lift stretched
    over a shorter swing, and its footholds moved back by half its ``advance``."""

    path: object
    kind = "step-path-duty"

    def evaluate(self, t):
        p = self.path
        _, u, in_swing = _cycle(t, p.duty, p.period, p.lift_off)
        swing = (p.advance * shape_rates("step", u, p.duty, p.period)
                 + p.lift * shape_rates("lift", u, p.duty, p.period))
        out = np.where(in_swing, swing, 0.0)
        out[0] = out[0] - 0.5 * p.advance
        return out[0], out[1], out[2]


@dataclass(frozen=True, eq=False)
class GaitCoupledDuty(Law):
    """The derivative of a :class:`legs.stepping.GaitCoupled` joint law (``law``) with
    respect to the duty factor. Its reach is ``2 F`` with, over the swing,
    ``F = -1/2 + u + (S(u) - u) / d`` (the foot's fore-aft position over the stance's length
    relative to the trunk), over the stance ``F = -1/2 + (1 - tau) / d``; its lift the swing's
    bump ``B(u)``."""

    law: object
    kind = "gait-coupled-duty"

    def evaluate(self, t):
        law = self.law
        d, T = law.duty, law.period
        tau, u, in_swing = _cycle(t, d, T, law.lift_off)
        if law.follows == "lift":
            out = np.where(in_swing, shape_rates("lift", u, d, T), 0.0)
        else:  # (S(u) - u) / d changes with d twice: through u and through 1 / d
            curved = shape_rates("step", u, d, T) - shape_rates("progress", u, d, T)
            bent = shape_values("step", u, d, T) - shape_values("progress", u, d, T)
            swing = shape_rates("progress", u, d, T) + curved / d - bent / d**2
            stance = np.array([-(1.0 - tau) / d**2, np.full_like(tau, 1.0 / (d**2 * T)),
                               np.zeros_like(tau)])
            out = 2.0 * np.where(in_swing, swing, stance)
        out = law.amplitude * out
        return out[0], out[1], out[2]


def duty_parameter(law, key: str, derivative: Law) -> tuple[float, Law] | None:
    """``gait.duty`` as a walking foot's ``law`` holds it (its ``duty`` and ``derivative``);
    None for another key."""
    return (float(law.duty), derivative) if key == "gait.duty" else None
