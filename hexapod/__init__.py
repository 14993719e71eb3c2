"""hexapod: equations of motion of constrained multibody systems in absolute coordinates.

Describe a system as a :class:`Scene`, build it once with :func:`assemble`, then run the
algorithms on the :class:`~hexapod.model.Model` with a :class:`~hexapod.model.Data` workspace::

    model = hexapod.assemble(scene)
    data = hexapod.Data()
    q, v = hexapod.consistent_state(model)
    v_dot = hexapod.forward_dynamics(model, data, 0.0, q, v)
    wrenches = hexapod.joint_wrenches(model, q, data.lam, data.Phi_v)
    result = hexapod.simulate(model, 2.0, method="dopri5-projection")
"""

import os

# The matrices of a mechanism are small (tens to a few thousand rows): OpenBLAS's threads cost
# far more than they save there, and on a busy machine a 180 x 150 QR takes 100 ms instead of
# 3 ms. One BLAS thread, unless the user chose otherwise (effective when NumPy is imported after
# hexapod, as by the command line).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from hexapod.assembly import assemble  # noqa: E402
from hexapod.dynamics import forward_dynamics
from hexapod.errors import (
    AssemblyError,
    HexapodError,
    InputFileError,
    IntegrationError,
    ModelError,
    SingularSystemError,
)
from hexapod.kinematics import (
    assemble_positions,
    consistent_state,
    degrees_of_freedom,
    solve_accelerations,
    solve_velocities,
)
from hexapod.model import Data, Model
from hexapod.reactions import JointWrenches, driver_efforts, joint_wrenches
from hexapod.scene import (
    GROUND,
    AppliedForce,
    AppliedTorque,
    Constant,
    CoordinateDriver,
    Distance,
    Fixed,
    Gait,
    Harmonic,
    Hermite,
    JointDriver,
    JointEffort,
    Particle,
    PlanarBody,
    Polynomial,
    Prismatic,
    Revolute,
    Scene,
    SpatialBody,
    Spherical,
    Spline,
    SpringDamper,
)
from hexapod.simulate import simulate
from hexapod.spatial import Placement, rotation_about_axis, rotation_from_rpy

__version__ = "0.1.0"

__all__ = [
    "GROUND", "AppliedForce", "AppliedTorque", "AssemblyError", "Constant", "CoordinateDriver",
    "Data", "Distance", "Fixed", "Gait", "Harmonic", "Hermite", "HexapodError", "InputFileError",
    "IntegrationError", "JointDriver", "JointEffort", "JointWrenches", "Model", "ModelError",
    "Particle", "Placement", "PlanarBody", "Polynomial", "Prismatic", "Revolute", "Scene",
    "SingularSystemError", "SpatialBody", "Spherical", "Spline", "SpringDamper", "assemble",
    "assemble_positions", "consistent_state", "degrees_of_freedom", "driver_efforts",
    "forward_dynamics", "joint_wrenches", "rotation_about_axis", "rotation_from_rpy",
    "simulate", "solve_accelerations", "solve_velocities",
]
