"""The motors' figure: each driven joint's operating points (speed, effort) over its motor's
torque-speed envelope at the joint (:mod:`hexapod.output.actuation`)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from hexapod.output.actuation import MotorCheck, speed_unit
from hexapod.output.panel_axes import light_ticks
from hexapod.scene.actuators import effort_limits

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PANEL_SIZE = (3.4, 2.8)  # inches per panel


def envelope_figure(checks: list[MotorCheck], title: str) -> Figure:
    """One panel per checked joint: its motor's envelope at the joint shaded (a DC motor's
    band ``|tau / tau_s + w / w_0| <= 1``, or a rated rectangle), the joint's path through
    (speed, effort) over the run, and its samples outside the envelope in red.

    Parameters
    ----------
    checks : list of MotorCheck
        The joints and their motors (:func:`hexapod.output.actuation.motor_checks`).
    title : str
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    columns = min(len(checks), max(1, math.ceil(math.sqrt(1.5 * len(checks)))))
    rows = math.ceil(len(checks) / columns)
    width, height = PANEL_SIZE[0] * columns, PANEL_SIZE[1] * rows + 0.7
    figure = Figure(figsize=(width, height))
    grid = figure.add_gridspec(rows, columns, left=0.8 / width, right=1 - 0.2 / width,
                               bottom=0.55 / height, top=1 - 0.7 / height, wspace=0.45,
                               hspace=0.6)
    figure.suptitle(title, fontsize=11)
    for k, check in enumerate(checks):
        ax = figure.add_subplot(grid[divmod(k, columns)])
        _panel(ax, check)
    return figure


def _panel(ax, check: MotorCheck) -> None:
    d = check.driver
    max_effort, no_load, rated_speed = check.actuator.joint_limits()
    reach = max(no_load or rated_speed, float(np.abs(d.rate).max())) * 1.1
    speeds = np.linspace(-reach, reach, 201)
    if no_load is not None:
        lower, upper = effort_limits(max_effort, no_load, speeds)
        ax.fill_between(speeds, lower, upper, color="tab:green", alpha=0.15, linewidth=0)
        ax.plot(speeds, upper, speeds, lower, color="tab:green", linewidth=0.8)
    else:
        box_x = [-rated_speed, rated_speed, rated_speed, -rated_speed, -rated_speed]
        box_y = [-max_effort, -max_effort, max_effort, max_effort, -max_effort]
        ax.fill(box_x, box_y, color="tab:green", alpha=0.15, linewidth=0)
        ax.plot(box_x, box_y, color="tab:green", linewidth=0.8)
    ax.plot(d.rate, d.effort, color="tab:blue", linewidth=1.0)
    outside = check.use > 1.0
    if outside.any():
        ax.plot(d.rate[outside], d.effort[outside], ".", color="tab:red", markersize=3)
    peak = max(float(np.abs(d.effort).max()), max_effort) * 1.15
    ax.set_xlim(-reach, reach)
    ax.set_ylim(-peak, peak)
    ax.axhline(0.0, color="0.6", linewidth=0.5)
    ax.axvline(0.0, color="0.6", linewidth=0.5)
    ax.set_xlabel(f"speed ({speed_unit(d)})", fontsize=8)
    ax.set_ylabel(f"effort ({d.unit})", fontsize=8)
    ax.set_title(f"{d.joint}: {check.actuator.name}", fontsize=9, y=1.0)
    light_ticks(ax, x_labels=True)
