"""The motion the drivers prescribe, alone (:func:`hexapod.algorithms.prescribed.prescribed_motion`,
a guided model's guides' kinematics): the phase path's motion plans and the exact samples give
the positions, velocities and accelerations of the exact inverse dynamics (whose accelerations
come from the saddle-point solve, an independent route), across the walking robot's change of
contact set with the feet's rows redundant with the guides; a motion the drivers do not fix is
refused."""

from __future__ import annotations

import numpy as np
import pytest
from robots import builtin_model

import hexapod as hx
from hexapod.algorithms.prescribed import PHASE_FROM_SAMPLES, prescribed_motion

from mechanisms import four_bar, pendulum


def _agree(motion, exact, tol: float, n: int | None = None) -> None:
    """Positions, velocities and accelerations within ``tol`` of those of the first ``n``
    samples of the inverse-dynamics result ``exact``, relative to their largest magnitude (or
    to one, in SI, when that is smaller)."""
    for mine, theirs in zip(motion, (exact.q[:n], exact.v[:n], exact.v_dot[:n]), strict=True):
        assert np.max(np.abs(mine - theirs)) <= tol * max(1.0, np.max(np.abs(theirs)))


def test_the_walking_robots_guides_give_the_exact_paths_motion_across_a_touch_down():
    kinematics = builtin_model("hexapod").guidance.kinematics
    times = np.linspace(0.15, 0.25, PHASE_FROM_SAMPLES + 1)  # a touch-down at 0.2 s
    exact = hx.inverse_dynamics(kinematics, times, method="saddle", check_limits=False)
    assert exact.redundant_rows  # the feet's rows on the ground repeat the guides'
    _agree(prescribed_motion(kinematics, times), exact, 1e-9)  # the motion plans
    _agree(prescribed_motion(kinematics, times[:5]), exact, 1e-9, 5)  # sample by sample


@pytest.mark.parametrize("count", [5, PHASE_FROM_SAMPLES + 8])
def test_a_driven_four_bar_moves_as_its_inverse_dynamics_says(count):
    law = hx.scene.Harmonic(offset=1.05, sin=[0.6], frequency=0.8)
    model = hx.assemble(four_bar(3, 1.05, law=law))
    times = np.linspace(0.0, 1.25, count)
    _agree(prescribed_motion(model, times), hx.inverse_dynamics(model, times, method="saddle"),
           1e-10)


@pytest.mark.parametrize("count", [3, PHASE_FROM_SAMPLES])
def test_a_motion_the_drivers_leave_free_is_refused(count):
    model = hx.assemble(pendulum("planar", 0.3))  # a pivot without a driver
    with pytest.raises(hx.SingularSystemError, match="leave 1 degree"):
        prescribed_motion(model, np.linspace(0.0, 1.0, count))
