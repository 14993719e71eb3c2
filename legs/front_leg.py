"""The left front leg (L1) of the hexapod of Dumitru, Marin and Margine, and the built-in leg
scenes.

The leg itself is built by :mod:`legs.leg` (layout A: the numbering of elements and joints is
documented there: ``F21`` is the wrench at joint 2, ``thc_levation``, exerted by element 1 on
element 2). The built-in scenes drive it with the walking robot's tripod laws over one stride of
0.5 s (the window of Fig. 7 of Dumitru, Marin and Margine) and load its foot with the ground's
reaction the walking robot gives it (:mod:`legs.loads`).

Design options of the built-in leg scenes: the gait, the stride period (or the walking speed)
and the scale, the three things :mod:`legs.loads` computes the robot's ground reactions for. The
reactions of the tripod gait at 0.5 s and 20:1 are kept in a table; any other gait, period or
scale has them computed by the walking robot's inverse dynamics when the scene is built (1000
samples of the robot: about a minute). The duty factor, a payload and the segments' lengths
change the robot's ground reactions too, but :mod:`legs.loads` computes them for the robot's
own (:data:`legs.robot.WALKING_DUTY`, no payload, the cockroach's proportions), so they are not
options of the leg scenes: vary them on the robot (``hexapod``) itself.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from hexapod import Scene
from hexapod.scene import AppliedForce
from legs.cockroach import MODEL_SCALE, STRIDE_PERIOD
from legs.gait import GAITS
from legs.leg import leg_scene


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
    least-wrench policy gives it (:mod:`legs.loads`: tabulated for the tripod gait at the
    built-in period and scale, otherwise computed by the robot's inverse dynamics, about a
    minute). The trunk of the walking robot moves at constant velocity, so the leg's joint
    wrenches are those it has in the robot.

    Raises
    ------
    ValueError
        ``gait``, ``period`` (s, > 0) or ``scale`` (> 0) out of range.
    """
    from legs.gait import leg_of
    from legs.loads import ground_load_laws
    from legs.robot import WALKING_DUTY, check_gait, check_number
    from legs.stepping import guided_leg

    check_gait(gait)
    period = check_number("period", period, 0.0, unit="s, the stride period")
    scale = check_number("scale", scale, 0.0, unit="geometric scale")
    position, side = leg_of(leg)
    lift_off = GAITS[gait].lift_off[leg]
    scene = guided_leg(position, WALKING_DUTY[gait], side=side, scale=scale, period=period,
                       lift_off=lift_off, name=name or f"{position}-leg")
    scene.add(AppliedForce("ground_reaction", "tarsus",
                           ground_load_laws(leg, gait, period, scale), point="foot"))
    return scene


def _built_in_leg(leg: str, name: str, gait: str, period, speed, scale) -> Scene:
    from legs.robot import check_number, stride_period, walking_pattern

    scale = check_number("scale", scale, 0.0, unit="geometric scale")
    period = stride_period(walking_pattern(gait, None), period, speed, scale)
    return walking_leg_scene(leg, gait, period, scale, name=name)


def front_leg_walking(*, gait: str = "tripod", period: float | None = None,
                      speed: float | None = None, scale: float = MODEL_SCALE) -> Scene:
    """Built-in ``front-leg``: the left front leg (L1) of the 20:1 cockroach-like robot, six
    driven revolute joints in the walking robot's tripod gait, its foot loaded by the ground's
    reaction in the walking robot.

    With no arguments, the built-in scene.

    Parameters
    ----------
    gait : {"tripod", "tetrapod", "wave"}
        The walking robot's gait (default ``"tripod"``), at its duty factor
        (:data:`legs.robot.WALKING_DUTY`: 0.6, 2/3, 5/6).
    period : float, optional
        Stride period (s, > 0; default 0.5). Give ``period`` or ``speed``, not both.
    speed : float, optional
        The robot's walking speed (m/s, > 0) instead of ``period``: the period is then
        ``GaitPattern.walking_speed(1, scale) / speed`` at the gait's walking duty factor
        (0.867 m/s for the tripod gait at the defaults).
    scale : float
        Geometric scale (> 0; default 20).

    Raises
    ------
    ValueError
        An option out of its range (the message names it and its range).

    Notes
    -----
    The foot's load is the ground's reaction in the walking robot: tabulated for the tripod
    gait at 0.5 s and 20:1, computed by the robot's inverse dynamics (about a minute) for any
    other gait, period or scale. The duty factor, a payload and the segments' lengths are not
    options here (:mod:`legs.loads` computes the reactions of the built-in robot only): vary
    them on ``hexapod``.
    """
    return _built_in_leg("L1", "front-leg", gait, period, speed, scale)


def middle_leg_walking(*, gait: str = "tripod", period: float | None = None,
                       speed: float | None = None, scale: float = MODEL_SCALE) -> Scene:
    """Built-in ``middle-leg``: the left middle leg (L2) of the 20:1 cockroach-like robot, as
    ``front-leg``.

    With no arguments, the built-in scene.

    Parameters
    ----------
    gait : {"tripod", "tetrapod", "wave"}
        The walking robot's gait (default ``"tripod"``), at its duty factor
        (:data:`legs.robot.WALKING_DUTY`: 0.6, 2/3, 5/6).
    period : float, optional
        Stride period (s, > 0; default 0.5). Give ``period`` or ``speed``, not both.
    speed : float, optional
        The robot's walking speed (m/s, > 0) instead of ``period`` (see ``front-leg``).
    scale : float
        Geometric scale (> 0; default 20).

    Raises
    ------
    ValueError
        An option out of its range (the message names it and its range).

    Notes
    -----
    As for ``front-leg``: loads tabulated for the tripod gait at 0.5 s and 20:1, otherwise
    computed (about a minute); no duty, payload or segment lengths here.
    """
    return _built_in_leg("L2", "middle-leg", gait, period, speed, scale)


def hind_leg_walking(*, gait: str = "tripod", period: float | None = None,
                     speed: float | None = None, scale: float = MODEL_SCALE) -> Scene:
    """Built-in ``hind-leg``: the left hind leg (L3) of the 20:1 cockroach-like robot, as
    ``front-leg``.

    With no arguments, the built-in scene.

    Parameters
    ----------
    gait : {"tripod", "tetrapod", "wave"}
        The walking robot's gait (default ``"tripod"``), at its duty factor
        (:data:`legs.robot.WALKING_DUTY`: 0.6, 2/3, 5/6).
    period : float, optional
        Stride period (s, > 0; default 0.5). Give ``period`` or ``speed``, not both.
    speed : float, optional
        The robot's walking speed (m/s, > 0) instead of ``period`` (see ``front-leg``).
    scale : float
        Geometric scale (> 0; default 20).

    Raises
    ------
    ValueError
        An option out of its range (the message names it and its range).

    Notes
    -----
    As for ``front-leg``: loads tabulated for the tripod gait at 0.5 s and 20:1, otherwise
    computed (about a minute); no duty, payload or segment lengths here.
    """
    return _built_in_leg("L3", "hind-leg", gait, period, speed, scale)
