"""The cockroach rebuilt: its legs placed by the engine's kinematics instead of its own inverse
kinematics, the walking robot built from its robot description by the general path, and the
figures of before kept to 1e-9.

``tests/data/cockroach_reference.npz`` holds the figures the cockroach's own inverse kinematics
gave (``tests/data/make_cockroach_reference.py``, written before it was deleted): every joint's
force and moment, every effort and the ground forces over one stride of each built-in scene of
the cockroach and of two design variants. The same numbers, to 1e-9 of the largest of each
quantity, say the motion is the same (the feet on the same paths, the joints the same angles,
rates and accelerations) and so is everything computed from it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from script_loader import load_script

REFERENCE = Path(__file__).resolve().parent / "data" / "cockroach_reference.npz"
TOLERANCE = 1e-9


SCRIPT = load_script("tests/data/make_cockroach_reference.py")


@pytest.mark.parametrize("name", ["front-leg", "middle-leg", "hind-leg", "hexapod",
                                  "hexapod-held", "hexapod-standing", "hexapod-tetrapod",
                                  "hexapod-femur-1.1"])
def test_the_cockroach_keeps_its_figures(name):
    reference = np.load(REFERENCE)
    assert np.array_equal(reference["times"], SCRIPT.TIMES)
    now = SCRIPT.figures(SCRIPT.cases()[name]())
    for key, value in now.items():
        before = reference[f"{name}:{key}"]
        if value.dtype.kind in "US":
            assert list(value) == list(before), key
            continue
        scale = np.nanmax(np.abs(before))
        assert np.nanmax(np.abs(value - before)) <= TOLERANCE * scale, (name, key)
