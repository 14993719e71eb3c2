"""Scene descriptions (layer 1): the mutable, validated input of :func:`hexapod.assemble`, their
files (TOML scenes, URDF, motion CSV) and the built-in scenes by name."""

from hexapod.scene.bodies import Particle, PlanarBody, SpatialBody
from hexapod.scene.drivers import CoordinateDriver, JointDriver
from hexapod.scene.element import GROUND
from hexapod.scene.forces import (
    AppliedForce,
    AppliedTorque,
    JointEffort,
    RotationalSpringDamper,
    SpringDamper,
)
from hexapod.scene.joints import (
    Cylindrical,
    Distance,
    Fixed,
    Joint,
    PlanarJoint,
    PointOnPlane,
    Prismatic,
    Revolute,
    Spherical,
    Universal,
)
from hexapod.scene.laws import Constant, Gait, Harmonic, Hermite, Law, Polynomial, Spline
from hexapod.scene.scene import LENGTH_UNITS, Scene

__all__ = [
    "GROUND", "LENGTH_UNITS", "AppliedForce", "AppliedTorque", "Constant", "CoordinateDriver",
    "Cylindrical", "Distance", "Fixed", "Gait", "Harmonic", "Hermite", "Joint", "JointDriver",
    "JointEffort", "Law", "Particle", "PlanarBody", "PlanarJoint", "PointOnPlane", "Polynomial",
    "Prismatic", "Revolute", "RotationalSpringDamper", "Scene", "SpatialBody", "Spherical",
    "Spline", "SpringDamper", "Universal",
]
