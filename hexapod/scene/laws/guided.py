"""The law of a joint whose motion the scene's guides decide.

A robot's motion is most often given where it is seen: the trunk's pose and each foot's path
(coordinate drivers with ``guide = true``). Its joints carry the efforts. A joint driver whose
law is :class:`Guided` follows whatever the guides make of its joint: the inverse dynamics first
solves the scene's kinematics with the guides as drivers (the engine's Newton solve, velocity and
acceleration equations, :func:`hexapod.inverse_dynamics`), then the dynamics with these joints
driven by the motion found and the guides left out, so that the efforts are the joints' and the
guides exert nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

from hexapod.errors import HexapodError
from hexapod.scene.laws.base import Law


@dataclass(frozen=True)
class Guided(Law):
    """The motion the scene's guides give a driven joint (no parameters).

    It is not a function of time on its own: only the inverse dynamics, which solves the guides'
    kinematics first, evaluates it (a simulation or an instant's analysis of such a scene is
    refused, saying so)."""

    kind = "guided"

    def evaluate(self, t):
        raise HexapodError("a 'guided' law is the motion the scene's guides give its joint, "
                           "which the inverse dynamics solves first (hexapod inverse, hexapod "
                           "report, hexapod.inverse_dynamics): simulate, or analyse an instant "
                           "of, the motion an inverse run found instead")
