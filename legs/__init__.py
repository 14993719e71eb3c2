"""Leg and robot models, and gaits, built with the public ``hexapod`` API."""

from legs.front_leg import front_leg_scene

__all__ = ["front_leg_scene"]
