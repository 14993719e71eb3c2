"""Scene descriptions: the mutable, validated input of :func:`hexapod.assemble`."""

from hexapod.scene.bodies import Particle, PlanarBody, SpatialBody
from hexapod.scene.drivers import CoordinateDriver, JointDriver
from hexapod.scene.element import GROUND
from hexapod.scene.forces import AppliedForce, AppliedTorque, JointEffort, SpringDamper
from hexapod.scene.joints import Distance, Fixed, Joint, Prismatic, Revolute, Spherical
from hexapod.scene.laws import Constant, Gait, Harmonic, Hermite, Law, Polynomial, Spline
from hexapod.scene.scene import LENGTH_UNITS, Scene

__all__ = [
    "GROUND", "LENGTH_UNITS", "AppliedForce", "AppliedTorque", "Constant", "CoordinateDriver",
    "Distance", "Fixed", "Gait", "Harmonic", "Hermite", "Joint", "JointDriver", "JointEffort",
    "Law", "Particle", "PlanarBody", "Polynomial", "Prismatic", "Revolute", "Scene",
    "SpatialBody", "Spherical", "Spline", "SpringDamper",
]
