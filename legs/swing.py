"""The swing's unit shapes, functions of its progress ``u`` from 0 (lift-off) to 1
(touch-down): the fore-aft smooth step ``S(u)``, the ninth-degree polynomial with zero first to
fourth derivatives at both ends, and the lift ``B(u) = 1024 u^5 (1 - u)^5`` (1 at the middle).
Every walking foot's path is made of them (:mod:`legs.stepping`, :mod:`legs.walker`)."""

from __future__ import annotations

import numpy as np

_STEP9 = np.polynomial.Polynomial([0, 0, 0, 0, 0, 126, -420, 540, -315, 70])
_BUMP = np.polynomial.Polynomial([0, 1]) ** 5 * np.polynomial.Polynomial([1, -1]) ** 5 * 1024
#: ``S`` and ``B``, each with its first and second derivatives
STEP_RATES = tuple(_STEP9.deriv(m) for m in range(3))
LIFT_RATES = tuple(_BUMP.deriv(m) for m in range(3))
#: their third derivatives (the duty factor's derivative of a path's acceleration)
STEP_JERK, LIFT_JERK = _STEP9.deriv(3), _BUMP.deriv(3)
