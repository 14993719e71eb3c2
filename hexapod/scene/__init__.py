"""Scene descriptions (layer 1): the mutable, validated input of :func:`hexapod.assemble`, their
files (TOML scenes, URDF, motion CSV) and the built-in scenes by name.

The elements of a scene (bodies, joints, drivers, force elements, contacts), the laws of time
that drive and load them, and the scene constants are public here, as ``hexapod.scene.Revolute``
or ``from hexapod.scene import Revolute``; the scene itself and its files are also public at the
top (``hexapod.Scene``, ``hexapod.read_scene``, ...).

Names are imported when first used, so that ``hexapod.scene.builtin`` (the default scene's name,
the built-in scenes) is read without loading NumPy or CasADi.
"""

from hexapod._support.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "hexapod.scene.scene": ["LENGTH_UNITS", "Scene"],
    "hexapod.scene.element": ["GROUND"],
    "hexapod.errors": ["Problem"],  # one problem of a description, in a ModelError
    "hexapod.scene.bodies": ["Particle", "PlanarBody", "SpatialBody"],
    "hexapod.scene.joints": ["Contact", "Cylindrical", "Distance", "Fixed", "Joint", "PlanarJoint",
                             "PointOnPlane", "Prismatic", "Revolute", "Spherical", "Universal"],
    "hexapod.scene.drivers": ["CoordinateDriver", "JointDriver", "PostureDriver"],
    "hexapod.scene.forces": ["AppliedForce", "AppliedTorque", "GroundContact",
                             "JointController", "JointEffort", "RotationalSpringDamper",
                             "SpringDamper"],
    "hexapod.scene.contacts": ["POLICIES", "GroundForces"],
    "hexapod.scene.laws": ["Constant", "Expression", "Gait", "Guided", "Harmonic", "Hermite", "Law",
                           "Polynomial", "Spline", "cycle_breaks"],
    # files, motions and the built-in scenes
    "hexapod.scene.reader": ["read_scene"],
    "hexapod.scene.actuators": ["Actuator", "ActuatorTable", "effort_limits", "read_actuators"],
    "hexapod.scene.writer": ["scene_text", "write_scene"],
    "hexapod.scene.urdf": ["read_urdf", "urdf_text"],
    "hexapod.scene.motion": ["Motion", "MotionWarning", "apply_motion", "read_motion"],
    "hexapod.scene.builtin": ["DEFAULT_SCENE", "builtin_scenes", "load_scene"],
})
