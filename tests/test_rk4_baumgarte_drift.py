"""RK4 with Baumgarte stabilisation on Bricard's mechanism (one redundant row at every pose).

At h = 1e-2 s the run once reported "finished" with an error of 1.3 of the motion: its states
drift off the constraints by the truncation error (phi about 4e-8), which lifts the redundant
row 3e-10 to 1e-9 away from the span of the others; the exact solve at each step's end decided
the rank afresh with the model's tolerance (1e-9), kept the row at t = 1.47 s, solved a system
singular to within the drift, and the accelerations it handed to the next step were 10 m/s^2
off (170 at t = 1.52 s): the mechanism swung on at another energy (-33.4 J instead of -29.4 J).
The step's end is now solved as its stages are, and the multipliers with the rank and the
redundant rows' check decided to the accuracy of the state.

Bounds: a fourth-order method at step ``h`` errs by about ``(h / tau)^4`` of the motion,
``tau = sqrt(L / g)`` (0.32 s here): 1e-6 at 1e-2 s, 6e-4 at 5e-2 s; asked within ten times.
The multipliers are bounded by the mechanism's weight and swing (28.5 N at most over the
motion, found by every method); those of a system singular to within the drift ran to 7e9.
"""

from __future__ import annotations

import numpy as np
import pytest

import hexapod.benchmarks as m
from hexapod.model.assemble import assemble
from hexapod.simulation.loop import simulate

G = 9.81


@pytest.fixture(scope="module")
def bricard():
    case = m.bricard(t_end=2.0)  # the run left the motion at 1.47 s
    return case, assemble(case.scene)


@pytest.mark.parametrize("step", [1e-2, 5e-2])
def test_bricard_follows_the_reference(bricard, step):
    case, model = bricard
    result = simulate(model, case.t_end, method="rk4-baumgarte", step=step, forces=False)
    assert result.status == "finished", result.message
    level = (step / np.sqrt(model.characteristic_length / G)) ** 4
    assert case.error(model, result.t, result.q) <= 10 * level
    assert result.energy_drift <= 10 * level
    # the constraint forces of a mechanism of 5 kg swinging at about 2 m/s
    assert np.abs(result.lam).max() < 100.0
