"""Forward simulation (layer 4): the integrator registry and contract, compiled kernels (the
contact schemes' in :mod:`~hexapod.simulation.contact_kernel`), the time loop, its results (the
joint controllers' tracking errors among them) and the diagnostics of a state."""

from hexapod._support.lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, {
    "hexapod.simulation.loop": ["simulate"],
    "hexapod.simulation.results": ["SimulationResult"],
    "hexapod.simulation.registry": ["DEFAULT_ATOL", "DEFAULT_METHOD", "DEFAULT_RTOL",
                                    "INTEGRATORS", "get_integrator", "register"],
    "hexapod.simulation.integrators": ["Integrator"],
    "hexapod.simulation.diagnostics": ["Diagnosis", "diagnose"],
    "hexapod.simulation.tracking": ["controller_names", "tracking_errors"],
    # a guided model's laws as an inverse run found its motion (to replay or simulate it)
    "hexapod.algorithms.inverse": ["motion_model"],
    # the joint controllers' gain rule (critically damped on each joint's reflected inertia)
    "hexapod.algorithms.joint_inertia": ["critical_gains"],
})
