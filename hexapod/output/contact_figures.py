"""Figures of a simulation with unilateral contacts: each contact's ground force against time
with the time the ground pushes it shaded, and the simulated gait diagram (when each contact is
closed), drawn by the same figure functions as the walking robot's report."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from hexapod.output.figures import gait_diagram_figure, ground_reaction_figure
from hexapod.simulation.results import SimulationResult


def pushed_intervals(times: np.ndarray, forces: np.ndarray) -> list[list[tuple[float, float]]]:
    """Per contact, the runs of saved states where the ground pushes it (a non-zero force),
    each from its first to its last state.

    Parameters
    ----------
    times : ndarray, shape (N,)
    forces : ndarray, shape (N, m, d)

    Returns
    -------
    list of list of (float, float)
    """
    out = []
    for k in range(forces.shape[1]):
        pushed = np.linalg.norm(forces[:, k], axis=1) > 0.0
        edges = np.diff(np.concatenate([[0], pushed.astype(int), [0]]))
        starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
        out.append([(float(times[a]), float(times[b])) for a, b in zip(starts, stops,
                                                                         strict=True)])
    return out


def contact_figure_builders(result: SimulationResult) -> dict[str, Callable]:
    """``contacts.png`` (each contact's ground force, world axes, in N and in body weights,
    pushed states shaded; an impact shows as the mean force of its step) and ``gait.png``
    (when each contact is pushed), as builders for
    :func:`hexapod.output.figures.render_figures`; none without contacts.

    Parameters
    ----------
    result : SimulationResult

    Returns
    -------
    dict of str to callable
    """
    if result.contact_forces is None or not result.contact_names:
        return {}
    model = result.model
    names = list(result.contact_names)
    forces = result.contact_forces
    if model.dimension == 2:  # the plane's x and y: fore-aft and vertical
        forces = np.stack([forces[..., 0], np.zeros_like(forces[..., 0]), forces[..., 1]],
                          axis=-1)
    pushed = pushed_intervals(result.t, result.contact_forces)
    weight = model.total_mass * float(np.linalg.norm(model.gravity))
    start, stop = float(result.t[0]), float(result.t[-1])
    return {"contacts.png": lambda: ground_reaction_figure(
                result.t, forces, names, pushed, weight,
                f"{model.name}: the ground's force on each contact ({result.method})"),
            "gait.png": lambda: gait_diagram_figure(
                names, pushed, start, stop, f"{model.name}: when the ground pushes each "
                "contact (simulated)")}
