"""Figures of a simulation with unilateral contacts and joint controllers: each contact's
ground force against time with the time the ground pushes it shaded, the simulated gait
diagram (when each contact is closed; beside a schedule when one is given), drawn by the same
figure functions as the walking robot's report, and each controller's tracking error."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from hexapod.output.figures import gait_diagram_figure, ground_reaction_figure
from hexapod.output.summary_parts import true_runs
from hexapod.simulation.results import SimulationResult
from hexapod.simulation.tracking import controller_names

if TYPE_CHECKING:
    from matplotlib.figure import Figure


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
        out.append([(float(times[a]), float(times[b])) for a, b in true_runs(pushed)])
    return out


def contact_figure_builders(result: SimulationResult,
                            scheduled: list | None = None) -> dict[str, Callable]:
    """``contacts.png`` (each contact's ground force, world axes, in N and in body weights,
    pushed states shaded; an impact shows as the mean force of its step) and ``gait.png``
    (when each contact is pushed), as builders for
    :func:`hexapod.output.figures.render_figures`; none without contacts.

    Parameters
    ----------
    result : SimulationResult
    scheduled : list, optional
        Per contact, the intervals a schedule puts it on the ground (a walking robot's gait):
        drawn behind the simulated ones.

    Returns
    -------
    dict of str to callable
    """
    if result.contact_forces is None or not result.contact_names:
        return {}
    model = result.model
    names = result.ground_names()  # the legs', as the GRx:<leg> columns
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
                "contact" + (" (simulated)" if scheduled is None else
                             ", simulated and scheduled"), scheduled)}


def tracking_figure_builders(result: SimulationResult) -> dict[str, Callable]:
    """``tracking.png``: each joint controller's tracking error against time (mrad; with more
    than eight controllers the eight with the largest errors named, the others grey), as a
    builder for :func:`hexapod.output.figures.render_figures`; none without controllers.

    Parameters
    ----------
    result : SimulationResult

    Returns
    -------
    dict of str to callable
    """
    if result.tracking is None or not result.tracking.shape[1]:
        return {}
    return {"tracking.png": lambda: tracking_figure(
        result.t, result.tracking, list(controller_names(result.model)),
        f"{result.model.name}: joint tracking errors ({result.method})")}


def tracking_figure(t: np.ndarray, errors: np.ndarray, names: list[str],
                    title: str) -> Figure:
    """Tracking errors (N, k) of the controllers ``names`` against time, in mrad.

    Parameters
    ----------
    t : ndarray, shape (N,)
    errors : ndarray, shape (N, k)
        rad.
    names : list of str
    title : str

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    figure = Figure(figsize=(9.5, 4.2))
    ax = figure.subplots()
    peaks = np.abs(errors).max(axis=0)
    named = set(np.argsort(-peaks)[:8].tolist())
    for k, name in enumerate(names):
        if k in named:
            ax.plot(t, 1e3 * errors[:, k], linewidth=1.0, label=f"{name} ({1e3 * peaks[k]:.3g})")
        else:
            ax.plot(t, 1e3 * errors[:, k], color="0.7", linewidth=0.6)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("joint angle - target (mrad)")
    ax.grid(True, linewidth=0.4, alpha=0.6)
    ax.legend(fontsize=7, title="peak |error| (mrad)", title_fontsize=7, loc="upper left",
              bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax.set_title(title, fontsize=10)
    figure.tight_layout()
    return figure
