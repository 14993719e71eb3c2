"""The public ``assemble``: the model layer's, with the solver of guided joints' motion
registered (:mod:`hexapod.model.guided_motion`): the guides' kinematics solved at the times
asked as the inverse dynamics solves it (:func:`hexapod.algorithms.guided.guides_motion`: from
the scene's written pose, along the times), and the guided joints' coordinates along it
(:func:`hexapod.algorithms.guided.guided_coordinates`); guides out of the joints' reach are
named."""

from __future__ import annotations

import numpy as np

from hexapod.algorithms.guided import guided_coordinates, guides_motion
from hexapod.model import assemble
from hexapod.model.guided_motion import register_guides_solver
from hexapod.model.model import Model

__all__ = ["assemble"]


def guides_motion_at(model: Model, t: np.ndarray) -> np.ndarray:
    """The guided joints' coordinates, rates and accelerations (3, G, n) that a guided
    ``model``'s guides give at the sorted times ``t``."""
    return np.array(guided_coordinates(model, *guides_motion(model, t)))


register_guides_solver(guides_motion_at)
