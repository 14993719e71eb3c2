"""The motors' figure: each driven joint's operating points (speed, effort) over its motor's
torque-speed envelope at the joint (:mod:`hexapod.output.actuation`); for a robot one panel per
joint type and motor, a line per leg."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from hexapod.output.actuation import MotorCheck, speed_unit
from hexapod.output.ground import joint_type, leg_groups
from hexapod.output.panel_axes import light_ticks
from hexapod.scene.actuators import effort_limits

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PANEL_SIZE = (3.4, 2.8)  # inches per panel


def envelope_figure(checks: list[MotorCheck], title: str) -> Figure:
    """One panel per checked joint: its motor's envelope at the joint shaded (a DC motor's
    band ``|tau / tau_s + w / w_0| <= 1``, or a rated rectangle), the joint's path through
    (speed, effort) over the run, and its samples outside the envelope in red. For a robot
    (joints named ``<leg>/<joint>``, two legs or more) one panel per joint type and motor,
    one line per leg.

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

    panels = _panels(checks)
    columns = min(len(panels), max(1, math.ceil(math.sqrt(1.5 * len(panels)))))
    rows = math.ceil(len(panels) / columns)
    width, height = PANEL_SIZE[0] * columns, PANEL_SIZE[1] * rows + 0.7
    figure = Figure(figsize=(width, height))
    grid = figure.add_gridspec(rows, columns, left=0.8 / width, right=1 - 0.2 / width,
                               bottom=0.55 / height, top=1 - 0.7 / height, wspace=0.45,
                               hspace=0.6)
    figure.suptitle(title, fontsize=11)
    for k, (name, group) in enumerate(panels.items()):
        ax = figure.add_subplot(grid[divmod(k, columns)])
        _panel(ax, name, group)
    return figure


def _panels(checks: list[MotorCheck]) -> dict[str, list[MotorCheck]]:
    """The checks drawn together: per joint type and motor for a robot, else one by one."""
    names = [c.driver.joint for c in checks]
    if leg_groups(names) is None:
        return {f"{c.driver.joint}: {c.actuator.name}": [c] for c in checks}
    panels: dict[str, list[MotorCheck]] = {}
    for check in checks:
        key = f"{joint_type(check.driver.joint)}: {check.actuator.name}"
        panels.setdefault(key, []).append(check)
    return panels


def _panel(ax, name: str, group: list[MotorCheck]) -> None:
    check, d = group[0], group[0].driver  # one motor: one envelope
    max_effort, no_load, rated_speed = check.actuator.joint_limits()
    fastest = max(float(np.abs(c.driver.rate).max()) for c in group)
    reach = max(no_load or rated_speed, fastest) * 1.1
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
    for c in group:
        leg = c.driver.joint.partition("/")[0] if len(group) > 1 else None
        ax.plot(c.driver.rate, c.driver.effort, linewidth=1.0, label=leg)
        outside = c.use > 1.0
        if outside.any():
            ax.plot(c.driver.rate[outside], c.driver.effort[outside], ".", color="tab:red",
                    markersize=3)
    if len(group) > 1:
        ax.legend(fontsize=6, ncols=2, loc="upper right", frameon=False)
    peak = max(max(float(np.abs(c.driver.effort).max()) for c in group), max_effort) * 1.15
    ax.set_xlim(-reach, reach)
    ax.set_ylim(-peak, peak)
    ax.axhline(0.0, color="0.6", linewidth=0.5)
    ax.axvline(0.0, color="0.6", linewidth=0.5)
    ax.set_xlabel(f"speed ({speed_unit(d)})", fontsize=8)
    ax.set_ylabel(f"effort ({d.unit})", fontsize=8)
    ax.set_title(name, fontsize=9, y=1.0)
    light_ticks(ax, x_labels=True)
