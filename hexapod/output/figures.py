"""Figures of the liaison force report, as PNG bytes (matplotlib, imported when first drawn).

The style is that of Fig. 7 of Dumitru, Marin and Margine: the components of a joint's force and
their magnitude against time, one panel per joint. Figures are drawn on
:class:`matplotlib.figure.Figure` directly (no pyplot, no display, no global state), so they render
on machines without a screen.
"""

from __future__ import annotations

import io
import math

import numpy as np

COMPONENT_COLOURS = ("tab:red", "tab:green", "tab:blue")
PANEL_SIZE = (3.6, 2.5)  # inches per panel


def _figure(panels: int, title: str, twin: bool = False):
    """A grid of panels with fixed margins (constrained layout costs seconds for many
    panels); ``twin`` leaves room for a right-hand axis in each panel."""
    from matplotlib.figure import Figure

    columns = min(panels, max(1, math.ceil(math.sqrt(1.5 * panels))))
    rows = math.ceil(panels / columns)
    width, height = PANEL_SIZE[0] * columns, PANEL_SIZE[1] * rows + 0.6
    figure = Figure(figsize=(width, height))
    axes = figure.subplots(rows, columns, sharex=True, squeeze=False).ravel()
    right = 0.75 if twin else 0.2  # inches
    figure.subplots_adjust(left=0.75 / width, right=1 - right / width, bottom=0.5 / height,
                           top=1 - 0.65 / height, wspace=0.55 if twin else 0.3, hspace=0.45)
    for extra in axes[panels:]:
        extra.set_visible(False)
    figure.suptitle(title)
    return figure, axes[:panels], columns


def _finish_panels(axes, columns: int) -> None:
    for k, ax in enumerate(axes):
        ax.grid(True, linewidth=0.4, alpha=0.6)
        ax.tick_params(labelsize=8)
        if k >= len(axes) - columns:
            ax.set_xlabel("t (s)")
            ax.xaxis.set_tick_params(labelbottom=True)


def png_bytes(figure, dpi: int = 110) -> bytes:
    """A :class:`matplotlib.figure.Figure` rendered as PNG bytes (at ``dpi`` dots per inch)."""
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=dpi)
    return buffer.getvalue()


def wrench_figure(times: np.ndarray, values: np.ndarray, names: list[str], symbol: str,
                  unit: str, title: str):
    """Components and magnitude of vectors ``values`` (N, panels, 3), e.g. every joint's force,
    against time: one panel per vector, titled by ``names``."""
    figure, axes, columns = _figure(len(names), title)
    for k, (ax, name) in enumerate(zip(axes, names, strict=True)):
        for c, colour in enumerate(COMPONENT_COLOURS):
            ax.plot(times, values[:, k, c], color=colour, linewidth=1.0,
                    label=f"{symbol}{'xyz'[c]}")
        ax.plot(times, np.linalg.norm(values[:, k], axis=1), color="black", linewidth=1.6,
                label=f"|{symbol}|")
        ax.set_title(name, fontsize=9)
        ax.set_ylabel(unit, fontsize=8)
    _finish_panels(axes, columns)
    axes[0].legend(fontsize=7, ncols=2, loc="best")
    return figure


def effort_figure(times: np.ndarray, efforts: list[tuple[str, str, np.ndarray, np.ndarray]],
                  title: str):
    """Each actuator's effort (solid, left axis) and power (dashed, right axis) against time;
    ``efforts`` holds (name, unit of the effort, effort, power) per actuator."""
    figure, axes, columns = _figure(len(efforts), title, twin=True)
    for ax, (name, unit, effort, power) in zip(axes, efforts, strict=True):
        ax.plot(times, effort, color="tab:blue", linewidth=1.3)
        ax.set_ylabel(f"effort ({unit})", fontsize=8, color="tab:blue")
        twin = ax.twinx()
        twin.plot(times, power, color="tab:orange", linewidth=1.0, linestyle="--")
        twin.set_ylabel("power (W)", fontsize=8, color="tab:orange")
        twin.tick_params(labelsize=8)
        ax.set_title(name, fontsize=9)
    _finish_panels(axes, columns)
    return figure


def trajectory_figure(times: np.ndarray, trajectories: dict[str, np.ndarray], title: str):
    """Paths of points (e.g. the feet): side view (x, z), top view (x, y), and the coordinates
    against time; a dot marks each path's start."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(13.0, 4.2), layout="constrained")
    side, top, timeline = figure.subplots(1, 3)
    colours = [f"C{k % 10}" for k in range(len(trajectories))]
    for colour, (name, path) in zip(colours, trajectories.items(), strict=True):
        for ax, (i, j) in ((side, (0, 2)), (top, (0, 1))):
            ax.plot(path[:, i], path[:, j], color=colour, linewidth=1.3, label=name)
            ax.plot(path[0, i], path[0, j], "o", color=colour, markersize=4)
    for ax, (x, y), view in ((side, "xz", "side view"), (top, "xy", "top view")):
        ax.set_xlabel(f"{x} (m)")
        ax.set_ylabel(f"{y} (m)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(view, fontsize=9)
    if len(trajectories) == 1:
        path = next(iter(trajectories.values()))
        for c, colour in enumerate(COMPONENT_COLOURS):
            timeline.plot(times, path[:, c] - path[0, c], color=colour, label="xyz"[c])
        timeline.set_ylabel("displacement from start (m)")
    else:
        for colour, path in zip(colours, trajectories.values(), strict=True):
            timeline.plot(times, path[:, 2], color=colour)
        timeline.set_ylabel("z (m)")
    timeline.set_xlabel("t (s)")
    timeline.set_title("against time", fontsize=9)
    for ax in (side, top, timeline):
        ax.grid(True, linewidth=0.4, alpha=0.6)
        ax.tick_params(labelsize=8)
    (timeline if len(trajectories) == 1 else top).legend(fontsize=7)
    figure.suptitle(title)
    return figure
