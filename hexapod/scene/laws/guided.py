"""The law of a joint whose motion the scene's guides decide.

A robot's motion is most often given where it is seen: the trunk's pose and each foot's path
(coordinate drivers with ``guide = true``). Its joints carry the efforts. A joint driver whose
law is :class:`Guided` follows whatever the guides make of its joint: the inverse dynamics first
solves the scene's kinematics with the guides as drivers (the engine's Newton solve, velocity and
acceleration equations, :func:`hexapod.inverse_dynamics`), then the dynamics with these joints
driven by the motion found and the guides left out, so that the efforts are the joints' and the
guides exert nothing. Every other analysis reads the joint's law in the assembled model: the
guides' kinematics solved at the times it asks (:mod:`hexapod.model.guided_motion`).
"""

from __future__ import annotations

from dataclasses import dataclass

from hexapod.errors import HexapodError
from hexapod.scene.laws.base import Law


@dataclass(frozen=True)
class Guided(Law):
    """The motion the scene's guides give a driven joint (no parameters).

    It is not a function of time on its own: the assembled model (``hexapod.assemble``) gives
    the joint the motion its guides give it, solved by the engine's kinematics at the times
    asked; the law alone has no value."""

    kind = "guided"

    def evaluate(self, t):
        raise HexapodError("a 'guided' law is the motion the scene's guides give its joint, "
                           "which the engine's kinematics solves: evaluate it in the scene's "
                           "model (hexapod.assemble), not alone")
