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

Public means listed in ``hexapod.__all__`` (the pipeline: errors, scenes and their files, the
model, the algorithms, simulation, sweeps and their results) or in the ``__all__`` of a public
namespace:

* :mod:`hexapod.scene`: the elements of a scene (``hx.scene.Revolute``, ``hx.scene.SpatialBody``,
  ...), the laws of time (``hx.scene.Harmonic``, ...) and the scene constants (``GROUND``,
  ``LENGTH_UNITS``);
* :mod:`hexapod.output`: what a report is made of (tables, descriptions, figures, atomic
  writers);
* :mod:`hexapod.spatial`: :class:`~hexapod.spatial.Placement` and the rotation helpers;
* :mod:`hexapod.simulation`: the integrators and the defaults (``DEFAULT_METHOD``, ...);
* :mod:`hexapod.benchmarks` (cases with independent references, the studies),
  :mod:`hexapod.minimal` (joint-coordinate forms) and :mod:`hexapod.sweeps` (design studies).

Names are imported when first used, so ``import hexapod`` is quick.
"""

from hexapod._support.lazy import attach
from hexapod._version import __version__ as __version__

__getattr__, __dir__, __all__ = attach(__name__, {
    "hexapod.errors": ["AssemblyError", "HexapodError", "InputFileError", "IntegrationError",
                       "ModelError", "SingularSystemError"],
    "hexapod._support.execution": ["Execution", "executing"],
    # scenes and their files
    "hexapod.scene.scene": ["Scene"],
    "hexapod.scene.builtin": ["builtin_scenes", "load_scene"],
    "hexapod.scene.reader": ["read_scene"],
    "hexapod.scene.writer": ["write_scene"],
    "hexapod.scene.urdf": ["read_urdf"],
    "hexapod.scene.motion": ["apply_motion", "read_motion"],
    # the model
    "hexapod.model": ["Data", "Model"],
    "hexapod.algorithms.assembly": ["assemble"],
    # algorithms at a state, and over a motion
    "hexapod.algorithms.kinematics": ["assemble_positions", "body_poses", "consistent_state",
                                      "degrees_of_freedom", "marker_trajectories",
                                      "solve_accelerations", "solve_velocities"],
    "hexapod.algorithms.dynamics": ["forward_dynamics"],
    "hexapod.algorithms.liaison": ["JointWrenches", "driver_efforts", "joint_wrenches",
                                   "wrenches_from_multipliers"],
    "hexapod.algorithms.inverse": ["InverseResult", "inverse_dynamics"],
    "hexapod.algorithms.sensitivity": ["inverse_sensitivities"],
    "hexapod.algorithms.balance": ["BodyBalance", "body_balance"],
    "hexapod.algorithms.joint_inertia": ["reflected_inertias"],
    "hexapod.algorithms.ground": ["ground_reactions"],
    "hexapod.algorithms.topology": ["BodyJointGraph", "Mobility", "VectorNetwork",
                                    "body_joint_graph", "mobility", "vector_network"],
    # in time
    "hexapod.simulation.loop": ["simulate"],
    "hexapod.simulation.results": ["SimulationResult"],
    "hexapod.simulation.registry": ["INTEGRATORS", "get_integrator", "register"],
    "hexapod.simulation.integrators": ["Integrator"],
    "hexapod.simulation.diagnostics": ["Diagnosis", "diagnose"],
    "hexapod.sweeps.run": ["sweep"],
    # namespaces
    "hexapod.scene": ["scene"],
    "hexapod.output": ["output"],
    "hexapod.spatial": ["spatial"],
    "hexapod.simulation": ["simulation"],
    "hexapod.benchmarks": ["benchmarks"],
    "hexapod.minimal": ["minimal"],
    "hexapod.sweeps": ["sweeps"],
})
