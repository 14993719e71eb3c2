"""Scene descriptions (layer 1): the mutable, validated input of :func:`hexapod.assemble`, their
files (TOML scenes, URDF, motion CSV) and the built-in scenes by name.

Names are imported when first used, so that ``hexapod.scene.builtin`` (the default scene's name,
the built-in scenes) is read without loading NumPy or CasADi.
"""

from hexapod._support.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "hexapod.scene.bodies": ["Particle", "PlanarBody", "SpatialBody"],
    "hexapod.scene.drivers": ["CoordinateDriver", "JointDriver"],
    "hexapod.scene.contacts": ["POLICIES", "GroundForces"],
    "hexapod.scene.element": ["GROUND"],
    "hexapod.scene.forces": ["AppliedForce", "AppliedTorque", "JointEffort",
                             "RotationalSpringDamper", "SpringDamper"],
    "hexapod.scene.joints": ["Contact", "Cylindrical", "Distance", "Fixed", "Joint", "PlanarJoint",
                             "PointOnPlane", "Prismatic", "Revolute", "Spherical", "Universal"],
    "hexapod.scene.laws": ["Constant", "Expression", "Gait", "Harmonic", "Hermite", "Law",
                           "Polynomial", "Spline"],
    "hexapod.scene.scene": ["LENGTH_UNITS", "Scene"],
})
