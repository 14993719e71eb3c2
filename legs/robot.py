"""The hexapod: six legs attached by prefix (``L1`` ... ``R3``) to a trunk fixed in the world.

Each leg is :func:`legs.leg.leg_scene` placed at its thorax-coxa point (the leg note's
section 3 [E], scaled); the trunk's reference frame is its centre of mass (x forward, y left,
z up). With a gait, every joint is driven and each foot carries the ground's reaction during
its stance (seed 001's prescribed generalized forces); the trunk is held, so the joints' loads
are those of a robot walking at constant height and speed.
"""

from __future__ import annotations

import numpy as np

from hexapod import AppliedForce, Fixed, Placement, Scene, SpatialBody
from legs.cockroach import MODEL_SCALE, SEGMENTS, STRIDE_PERIOD, THC_POINT_MM, TRUNK, bracket
from legs.gait import GAITS, LEG_NAMES, leg_of
from legs.leg import leg_scene

GRAVITY = 9.81


def robot_mass(scale: float = MODEL_SCALE) -> float:
    """Trunk plus six legs (kg)."""
    legs = sum(2 * (sum(s.scaled(scale)[1] for s in SEGMENTS[leg])
                    + 2 * bracket(leg).scaled(scale)[1]) for leg in SEGMENTS)
    return TRUNK["mass_g"] * 1e-3 * scale**3 + legs


def robot_weight(scale: float = MODEL_SCALE) -> float:
    return robot_mass(scale) * GRAVITY


def hexapod_scene(gait: str | None = "tripod", period: float = STRIDE_PERIOD,
                  scale: float = MODEL_SCALE, loads: bool = True, name: str = "hexapod") -> Scene:
    """Six legs on a fixed trunk; with ``gait``, driven and (with ``loads``) loaded in stance."""
    scene = Scene(name, dimension=3, length_unit="m")
    scene.add(SpatialBody("trunk", TRUNK["mass_g"] * 1e-3 * scale**3,
                          np.array(TRUNK["inertia"]) * scale**5))
    scene.add(Fixed("trunk_hold", "ground", "trunk"))
    pattern = GAITS[gait] if gait else None
    for leg in LEG_NAMES:
        position, side = leg_of(leg)
        x, y, z = THC_POINT_MM[position]
        point = np.array([x, y if side == "L" else -y, z]) * 1e-3 * scale
        laws = pattern.joint_laws(leg, period) if pattern else None
        scene.attach(leg_scene(position, side, scale, laws), leg, base="trunk",
                     placement=Placement(point))
        if pattern and loads:
            scene.add(AppliedForce(f"{leg}/ground_reaction", f"{leg}/tarsus",
                                   pattern.stance_load(leg, robot_weight(scale), period),
                                   point="foot"))
    return scene


def hexapod_walking() -> Scene:
    """Built-in ``hexapod``: tripod gait, ground reactions in stance."""
    return hexapod_scene()
