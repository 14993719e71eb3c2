"""A guided model's joints in a forward simulation: their motion, solved from the guides.

A simulation reads its laws at every stage of every step. The joints that follow a scene's
guides (:mod:`hexapod.scene.laws.guided`) have no law of their own: here each gets one whose
value at any times is the guides' kinematics solved there (the kinematics model's inverse run,
its positions' joint coordinates, :func:`hexapod.algorithms.guided.guided_coordinates`). Such a
law costs a run, so it is costly and the simulation reads it from a table built once
(:mod:`hexapod.model.tabulation`), over one period when every law of the guides repeats.
"""

from __future__ import annotations

import numpy as np

from hexapod.algorithms.guided import guided_coordinates
from hexapod.algorithms.inverse import inverse_dynamics
from hexapod.model.model import Model
from hexapod.model.tabulation import ComputedLaw, shared_period


def simulated_model(model: Model) -> Model:
    """``model`` with each guided joint's law the motion its guides give it (solved at the
    times asked, a :class:`~hexapod.model.tabulation.ComputedLaw`); any other model itself."""
    if model.guidance is None:
        return model
    kinematics = model.guidance.kinematics

    def solve(t: np.ndarray) -> np.ndarray:
        motion = inverse_dynamics(kinematics, t)
        return np.array(guided_coordinates(model, motion.q, motion.v, motion.v_dot))

    period = shared_period(kinematics.laws)
    laws = list(model.laws)
    for k, index in enumerate(model.guidance.laws):
        laws[index] = ComputedLaw(solve, k, period, tuple(kinematics.laws))
    return model.with_laws(tuple(laws), model.digest)
