"""The public ``assemble``: the model layer's, with the solver of guided joints' motion
registered (:mod:`hexapod.model.guided_motion`): the guides' kinematics solved at the times
asked as the inverse dynamics solves it (:func:`hexapod.algorithms.guided.followed_guides`: from
the scene's written pose, along the times), with the guided joints' coordinates along it;
guides out of the joints' reach are named."""

from __future__ import annotations

import numpy as np

from hexapod.algorithms.guided import followed_guides
from hexapod.model import assemble
from hexapod.model.guided_motion import register_guides_solver
from hexapod.model.model import Model

__all__ = ["assemble"]


def guides_motion_at(model: Model, t: np.ndarray) -> np.ndarray:
    """The guided joints' coordinates, rates and accelerations (3, G, n) that a guided
    ``model``'s guides give at the sorted times ``t``."""
    return np.array(followed_guides(model, t)[3])


register_guides_solver(guides_motion_at)
