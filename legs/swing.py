"""A walking foot's swing: where it is in its cycle (:func:`swing_schedule`,
:func:`stance_progress`) and its unit shapes, functions of its progress ``u`` from 0
(lift-off) to 1 (touch-down): the fore-aft smooth step ``S(u)``, the ninth-degree polynomial
with zero first to fourth derivatives at both ends, and the lift ``B(u) = 1024 u^5 (1 -
u)^5`` (1 at the middle). Every walking foot's path is made of them (:mod:`legs.stepping`,
:mod:`legs.walker`, :mod:`legs.turning`)."""

from __future__ import annotations

import numpy as np

_STEP9 = np.polynomial.Polynomial([0, 0, 0, 0, 0, 126, -420, 540, -315, 70])
_BUMP = np.polynomial.Polynomial([0, 1]) ** 5 * np.polynomial.Polynomial([1, -1]) ** 5 * 1024
#: ``S`` and ``B``, each with its first and second derivatives
STEP_RATES = tuple(_STEP9.deriv(m) for m in range(3))
LIFT_RATES = tuple(_BUMP.deriv(m) for m in range(3))
#: their third derivatives (the duty factor's derivative of a path's acceleration)
STEP_JERK, LIFT_JERK = _STEP9.deriv(3), _BUMP.deriv(3)


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
