"""The scale of a scene's motion, and the tests a fixed step must pass.

The characteristic time, speed, acceleration and energy of a scene (gravity moving it by its own
size) give tolerances their units and round-off its size; a fixed-step method's step is judged
against them by the branch and energy tests of :meth:`Integrator.step
<hexapod.simulation.integrators.base.Integrator.step>`, which reads its thresholds here.
"""

from __future__ import annotations

import numpy as np

from hexapod.model.model import Model
from hexapod.simulation.methods import CHARACTERISTIC_TIME

#: a step of a fixed-step method whose velocities change by more than this many times the step
#: times the larger of the accelerations at its ends (kinetic-energy norm) is refused, and
#: halved (:meth:`Integrator._jumps_branch`). RATTLE's kicks give ``v1 - v0 = h (a0 + a1) / 2``
#: to ``O(h^2)``, so a healthy step stays near 1 (0.95 to 1.0 over the N-four-bar's runs, 0.98
#: at its flat poses); Newton's method landing on another branch of the constraints (or on a
#: spurious root of the step's equations) changes them by the whole speed: RATTLE at h = 2e-2 s
#: on the N-four-bar with 40 windows went from ratio 1 to 2.1 and 3.2 in two steps at 10.6 s,
#: and its energy from 612 J to 2850 J, and went on as if nothing had happened
BRANCH_JUMP = 1.5
#: a step of a fixed-step method on a conservative scene whose energy changes by more than this
#: fraction of the largest kinetic energy of the run so far is refused (RATTLE halves it) or
#: ends the run (:meth:`Integrator._energy_jump`). Healthy runs stay below 1e-2 (RATTLE: 3e-5 on
#: the N-four-bar at h = 1e-2 s, 2e-3 on the pendulum at 1000 steps per 20 periods, 8.5e-3 on
#: the stretched leg); RATTLE at h = 4e-2 s on the N-four-bar with 20 windows lost a quarter of
#: it in one step at a flat pose and ended 45 % off, at ten steps per period on the pendulum two
#: thirds, reported finished
ENERGY_JUMP = 5e-2
#: the relative size of round-off below which the two tests above see nothing: on a scene at
#: rest (the hexapod standing) the accelerations and the energy's changes are round-off, and
#: measured against themselves they refused every step
ROUND_OFF = 1e-9


def characteristic_time(model: Model) -> float:
    """``sqrt(L / |g|)`` (s), ``L`` the scene's characteristic length: the time over which
    gravity moves a body of the scene by about its size (a pendulum of length ``L`` swings
    through a radian in about that time), so that a velocity error ``e`` makes a position error
    of about ``e sqrt(L / |g|)``; without gravity :data:`CHARACTERISTIC_TIME`."""
    gravity = float(np.linalg.norm(model.gravity))
    length = float(model.characteristic_length)
    if not (gravity > 0 and np.isfinite(gravity) and length > 0):
        return CHARACTERISTIC_TIME
    return float(np.sqrt(length / gravity))


def motion_scales(model: Model) -> tuple[float, float, float]:
    """The scene's characteristic speed, acceleration and energy in the kinetic-energy norm
    (``sqrt(m_total) L / tau``, ``sqrt(m_total) L / tau^2``, ``m_total L^2 / tau^2``; ``L`` the
    characteristic length, ``tau`` :func:`characteristic_time`): what a motion of the whole
    scene by its own size in its own time is, to measure round-off against."""
    mass = max(model.total_mass, np.finfo(float).tiny)
    length, time = float(model.characteristic_length), characteristic_time(model)
    return (np.sqrt(mass) * length / time, np.sqrt(mass) * length / time**2,
            mass * length**2 / time**2)
