"""The laws of a guided model's joints: the motion the scene's guides give them.

A joint that follows a scene's guides (:mod:`hexapod.scene.laws.guided`) has no law of its
own: its motion is the guides' kinematics solved at the times asked, and a kinematics solve is
an algorithm, a layer above the model. The model holds, in each such joint's law slot, a
costly :class:`~hexapod.model.tabulation.ComputedLaw` whose values come from the solver the
algorithms layer registers (:mod:`hexapod.algorithms.assembly` does when imported, which
``hexapod.assemble`` does). So an analysis at an instant, a simulation (which tabulates costly
laws once) and a report read the motion the guides give; the inverse dynamics, which solves
the guides over all its samples at once, puts laws exact at its samples in their place.
"""

from __future__ import annotations

from collections.abc import Callable

import casadi as ca
import numpy as np

from hexapod.errors import HexapodError
from hexapod.model.model import Model
from hexapod.model.tabulation import ComputedLaw, shared_period

#: ``(model, t) -> (3, G, n)``: the guided joints' coordinates, rates and accelerations at the
#: sorted times ``t``; registered by the algorithms layer.
_SOLVER: list[Callable[[Model, np.ndarray], np.ndarray]] = []


def register_guides_solver(solver: Callable[[Model, np.ndarray], np.ndarray]) -> None:
    """Make ``solver`` the one that gives guided joints their motion."""
    _SOLVER[:] = [solver]


class _GuidesMotion:
    """``t -> (3, G, n)`` of one guided model, by the registered solver. The last times asked
    and their motion are kept: the guided joints' laws evaluated one by one at the same times
    (a replay's, a plot's) share one solve of the guides instead of one each."""

    def __init__(self, model: Model):
        self.model = model
        self._last: tuple[np.ndarray, np.ndarray] | None = None

    def __call__(self, t: np.ndarray) -> np.ndarray:
        if not _SOLVER:
            raise HexapodError(f"model '{self.model.name}': its guided joints move as the "
                               "guides' kinematics solves them, which the algorithms do: "
                               "assemble with hexapod.assemble")
        last = self._last  # one read: another thread may replace it
        if last is not None and np.array_equal(last[0], t):
            return last[1].copy()
        motion = _SOLVER[0](self.model, t)
        self._last = (np.array(t, dtype=float), motion.copy())
        return motion


def with_guided_laws(model: Model) -> Model:
    """``model`` with each guided joint's law the motion its guides give it; a model without
    guides itself."""
    if model.guidance is None:
        return model
    kinematics = model.guidance.kinematics
    # the laws the guides' kinematics moves by (its constraints' and drivers'; not a force's):
    # its period and its changes of regime are the guided joints'
    phi, w = kinematics._sym.phi, kinematics._sym.w
    moving = tuple(law for law, used in zip(kinematics.laws, ca.which_depends(phi, w, 1, False),
                                           strict=True) if used) if w.numel() else ()
    solve, period = _GuidesMotion(model), shared_period(moving)
    laws = list(model.laws)
    for k, index in enumerate(model.guidance.laws):
        laws[index] = ComputedLaw(solve, k, period, moving)
    return model.with_laws(tuple(laws), model.digest)
