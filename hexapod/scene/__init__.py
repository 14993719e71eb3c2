"""Scene descriptions: the mutable, validated input of :func:`hexapod.assemble`.

Names are imported when first used, so that ``hexapod.scene.builtin`` (the default scene's name,
the built-in scenes) is read without loading NumPy or CasADi.
"""

from hexapod._support.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "hexapod.scene.bodies": ["Particle", "PlanarBody", "SpatialBody"],
    "hexapod.scene.drivers": ["CoordinateDriver", "JointDriver"],
    "hexapod.scene.element": ["GROUND"],
    "hexapod.scene.forces": ["AppliedForce", "AppliedTorque", "JointEffort", "SpringDamper"],
    "hexapod.scene.joints": ["Distance", "Fixed", "Joint", "Prismatic", "Revolute", "Spherical"],
    "hexapod.scene.laws": ["Constant", "Gait", "Harmonic", "Hermite", "Law", "Polynomial",
                           "Spline"],
    "hexapod.scene.scene": ["LENGTH_UNITS", "Scene"],
})
