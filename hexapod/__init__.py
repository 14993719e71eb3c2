"""hexapod: equations of motion of constrained multibody systems in absolute coordinates.

Describe a system as a :class:`Scene` (or load one: :func:`load_scene`), build it once with
:func:`assemble`, then run the algorithms on the model with a workspace from
``model.create_data()``; every algorithm reads ``f(model, data, t, q, v, ...)`` and leaves its
results in ``data``::

    import hexapod as hx

    model = hx.assemble(hx.load_scene("front-leg"))
    data = model.create_data()
    q, v = hx.consistent_state(model, data, 0.1)
    hx.forward_dynamics(model, data, 0.1, q, v)
    wrenches = hx.joint_wrenches(model, data)          # by the parent on the child
    result = hx.simulate(model, 2.0, method="dopri5-projection")

Names are imported when first used, so ``import hexapod`` is quick.
"""

from hexapod._support.lazy import attach
from hexapod._version import __version__ as __version__

__getattr__, __dir__, __all__ = attach(__name__, {
    "hexapod.errors": ["AssemblyError", "HexapodError", "InputFileError", "IntegrationError",
                       "ModelError", "SingularSystemError"],
    "hexapod.spatial": ["Placement", "rotation_about_axis", "rotation_from_rpy"],
    "hexapod.scene": ["GROUND", "AppliedForce", "AppliedTorque", "Constant", "CoordinateDriver",
                      "Distance", "Fixed", "Gait", "Harmonic", "Hermite", "JointDriver",
                      "JointEffort", "Particle", "PlanarBody", "Polynomial", "Prismatic",
                      "Revolute", "Scene", "SpatialBody", "Spherical", "Spline",
                      "SpringDamper"],
    "hexapod.scene.builtin": ["DEFAULT_SCENE", "builtin_scenes", "load_scene"],
    "hexapod.model": ["Data", "Model", "assemble"],
    "hexapod.algorithms.kinematics": ["assemble_positions", "consistent_state",
                                      "degrees_of_freedom", "solve_accelerations",
                                      "solve_velocities"],
    "hexapod.algorithms.dynamics": ["forward_dynamics"],
    "hexapod.algorithms.liaison": ["JointWrenches", "driver_efforts", "joint_wrenches"],
    "hexapod.simulation.loop": ["simulate"],
})

