"""The left front leg (L1) of the hexapod of Dumitru, Marin and Margine, and the built-in leg
scenes.

The leg itself is built by :mod:`legs.leg` (layout A: the numbering of elements and joints is
documented there: ``F21`` is the wrench at joint 2, ``thc_levation``, exerted by element 1 on
element 2). The built-in scenes drive it with the walking robot's tripod laws over one stride of
0.5 s (the window of Fig. 7 of Dumitru, Marin and Margine) and load its foot with the ground's
reaction the walking robot gives it (:mod:`legs.loads`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from hexapod import AppliedForce, Scene
from legs.cockroach import MODEL_SCALE, STRIDE_PERIOD
from legs.gait import GAITS
from legs.leg import JOINTS, leg_scene


def front_leg_scene(scale: float = MODEL_SCALE, gait: bool = True, phase: float = 0.0,
                    period: float = STRIDE_PERIOD, name: str = "front-leg") -> Scene:
    """The L1 leg hanging from a fixed trunk; with ``gait``, driven by the tripod's laws
    shifted by ``phase`` (rad); without, free (6 degrees of freedom). No load on the foot."""
    laws = None
    if gait:
        laws = {joint: replace(law, t0=law.t0 - phase / (2 * np.pi) * period)
                for joint, law in GAITS["tripod"].joint_laws("L1", period).items()}
    return leg_scene("front", "L", scale, laws, name)


def walking_leg_scene(leg: str = "L1", gait: str = "tripod", period: float = STRIDE_PERIOD,
                      scale: float = MODEL_SCALE, name: str | None = None) -> Scene:
    """One leg of the walking robot on a fixed trunk: driven by the robot's laws for ``gait``
    (:data:`legs.robot.WALKING_DUTY`), its foot loaded by the ground's reaction the robot's
    least-wrench policy gives it (:mod:`legs.loads`). The trunk of the walking robot moves at
    constant velocity, so the leg's joint wrenches are those it has in the robot."""
    from legs.gait import leg_of
    from legs.loads import ground_load_laws
    from legs.robot import WALKING_DUTY
    from legs.stepping import Stepping

    position, side = leg_of(leg)
    lift_off = GAITS[gait].lift_off[leg]
    laws = {joint: Stepping(position, joint, WALKING_DUTY[gait], period, lift_off)
            for joint in JOINTS}
    scene = leg_scene(position, side, scale, laws, name or f"{position}-leg")
    scene.add(AppliedForce("ground_reaction", "tarsus",
                           ground_load_laws(leg, gait, period, scale), point="foot"))
    return scene


def front_leg_walking() -> Scene:
    """Built-in ``front-leg``: the left front leg (L1) of the 20:1 cockroach-like robot, six
    driven revolute joints in the walking robot's tripod gait, its foot loaded by the ground's
    reaction in the walking robot."""
    return walking_leg_scene("L1", name="front-leg")


def middle_leg_walking() -> Scene:
    """Built-in ``middle-leg``: the left middle leg (L2) of the 20:1 cockroach-like robot, as
    ``front-leg``."""
    return walking_leg_scene("L2", name="middle-leg")


def hind_leg_walking() -> Scene:
    """Built-in ``hind-leg``: the left hind leg (L3) of the 20:1 cockroach-like robot, as
    ``front-leg``."""
    return walking_leg_scene("L3", name="hind-leg")
