"""Leg and robot models, and gaits, built with the public ``hexapod`` API."""

from legs.front_leg import front_leg_scene, walking_leg_scene
from legs.gait import GAITS, GaitPattern
from legs.leg import leg_geometry, leg_scene
from legs.robot import hexapod_scene

__all__ = ["GAITS", "GaitPattern", "front_leg_scene", "hexapod_scene", "leg_geometry",
           "leg_scene", "walking_leg_scene"]
