"""hexapod: equations of motion of constrained multibody systems in absolute coordinates.

Describe a system as a :class:`Scene` (or load one: :func:`load_scene`), build it once with
:func:`assemble`, then run the algorithms on the model with a workspace from
``model.create_data()``; an algorithm at one state reads ``f(model, data, t, q, v, ...)`` and
leaves its results in ``data``::

    import hexapod as hx

    model = hx.assemble(hx.load_scene("front-leg"))
    data = model.create_data()
    q, v = hx.consistent_state(model, data, 0.1)
    hx.forward_dynamics(model, data, 0.1, q, v)
    wrenches = hx.joint_wrenches(model, data)   # by the parent on the child, joint frame
    gait = hx.inverse_dynamics(model, times)    # a whole motion: efforts and wrenches
    run = hx.simulate(model, 2.0)               # forward simulation

Public means listed in ``hexapod.__all__``; the namespaces :mod:`hexapod.benchmarks` (cases with
independent references, the studies) and :mod:`hexapod.minimal` (joint-coordinate forms) hold
their own. Names are imported when first used, so ``import hexapod`` is quick.
"""

from hexapod._support.lazy import attach
from hexapod._version import __version__ as __version__

__getattr__, __dir__, __all__ = attach(__name__, {
    "hexapod._support.execution": ["Execution", "executing"],
    "hexapod.errors": ["AssemblyError", "HexapodError", "InputFileError", "IntegrationError",
                       "ModelError", "SingularSystemError"],
    "hexapod.spatial": ["Placement", "euler_parameters_from_rotation", "rotation_about_axis",
                        "rotation_from_euler_parameters", "rotation_from_rpy"],
    # describing a system
    "hexapod.scene": ["GROUND", "LENGTH_UNITS", "AppliedForce", "AppliedTorque", "Constant",
                      "Contact", "CoordinateDriver", "Cylindrical", "Distance", "Expression",
                      "Fixed", "Gait", "GroundForces",
                      "Harmonic", "Hermite", "Joint", "JointDriver", "JointEffort", "Law",
                      "Particle", "PlanarBody", "PlanarJoint", "PointOnPlane", "Polynomial",
                      "Prismatic", "Revolute", "RotationalSpringDamper", "Scene", "SpatialBody",
                      "Spherical", "Spline", "SpringDamper", "Universal"],
    # its files, and the built-in scenes
    "hexapod.scene.reader": ["read_scene"],
    "hexapod.scene.writer": ["scene_text", "write_scene"],
    "hexapod.scene.urdf": ["read_urdf", "urdf_text"],
    "hexapod.scene.motion": ["Motion", "MotionWarning", "apply_motion", "read_motion"],
    "hexapod.scene.builtin": ["DEFAULT_SCENE", "builtin_scenes", "load_scene"],
    # the model
    "hexapod.model": ["GROUND_INDEX", "Data", "Model", "assemble"],
    # algorithms at a state, and over a motion
    "hexapod.algorithms.kinematics": ["assemble_positions", "body_poses", "consistent_state",
                                      "degrees_of_freedom", "marker_trajectories",
                                      "solve_accelerations", "solve_velocities"],
    "hexapod.algorithms.dynamics": ["forward_dynamics"],
    "hexapod.algorithms.liaison": ["JointWrenches", "driver_efforts", "joint_wrenches",
                                   "wrenches_from_multipliers"],
    "hexapod.algorithms.inverse": ["InverseResult", "inverse_dynamics"],
    "hexapod.algorithms.balance": ["BodyBalance", "body_balance"],
    "hexapod.algorithms.ground": ["contact_weights", "ground_reactions"],
    "hexapod.algorithms.topology": ["BodyJointGraph", "Mobility", "VectorNetwork",
                                    "body_joint_graph", "mobility", "vector_network"],
    # simulation
    "hexapod.simulation.loop": ["simulate"],
    "hexapod.simulation.results": ["SimulationResult"],
    "hexapod.simulation.registry": ["DEFAULT_ATOL", "DEFAULT_METHOD", "DEFAULT_RTOL",
                                    "INTEGRATORS", "get_integrator", "register"],
    "hexapod.simulation.integrators": ["Integrator"],
    "hexapod.simulation.diagnostics": ["Diagnosis", "diagnose"],
    # what users read
    "hexapod.output.report": ["RunInfo", "agreement", "report_files", "wrench_label"],
    "hexapod.output.inverse_csv": ["inverse_columns", "inverse_csv_text", "inverse_table"],
    "hexapod.output.describe": ["describe_model", "describe_state", "format_model",
                                "format_state"],
    "hexapod.output.figures": ["COMPONENT_COLOURS", "effort_figure", "png_bytes",
                               "trajectory_figure", "wrench_figure"],
    "hexapod._support.files": ["write_atomically", "write_directory_atomically"],
    # design studies
    "hexapod.sweeps.run": ["sweep"],
    # namespaces
    "hexapod.benchmarks": ["benchmarks"],
    "hexapod.minimal": ["minimal"],
    "hexapod.sweeps": ["sweeps"],
})
