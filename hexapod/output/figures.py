"""Figures of the liaison force report, as PNG bytes (matplotlib, imported when first drawn).

The style is that of Fig. 7 of Dumitru, Marin and Margine: the components of a joint's force and
their magnitude against time, one panel per joint. Figures are drawn on
:class:`matplotlib.figure.Figure` directly (no pyplot, no display, no global state), so they render
on machines without a screen.
"""

from __future__ import annotations

import io
import math
import sys
from typing import TYPE_CHECKING

import numpy as np

from hexapod.output.panel_axes import few_ticks, light_scale, light_ticks

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: The colours of the x, y and z components in every figure.
COMPONENT_COLOURS = ("tab:red", "tab:green", "tab:blue")
PANEL_SIZE = (3.6, 2.5)  # inches per panel


#: Height (inches) of the row under a figure's title that holds its legend.
LEGEND_ROW = 0.35


def _figure(panels: int, title: str, twin: bool = False, legend: bool = False):
    """A grid of panels with fixed margins (constrained layout costs seconds for many
    panels); ``twin`` leaves room for a right-hand axis in each panel, ``legend`` a row under
    the title for the legend the panels share (:func:`_shared_legend`)."""
    from matplotlib.figure import Figure

    columns = min(panels, max(1, math.ceil(math.sqrt(1.5 * panels))))
    rows = math.ceil(panels / columns)
    extra = LEGEND_ROW if legend else 0.0
    width, height = PANEL_SIZE[0] * columns, PANEL_SIZE[1] * rows + 0.6 + extra
    figure = Figure(figsize=(width, height))
    right = 0.75 if twin else 0.2  # inches
    grid = figure.add_gridspec(rows, columns, left=0.75 / width, right=1 - right / width,
                               bottom=0.5 / height, top=1 - (0.65 + extra) / height,
                               wspace=0.55 if twin else 0.3, hspace=0.45)
    # only the panels drawn are made (an Axes costs as much to make as to draw), all sharing
    # the time axis, its tick labels on the lowest panel of each column
    axes = [figure.add_subplot(grid[0, 0])]
    axes += [figure.add_subplot(grid[divmod(k, columns)], sharex=axes[0])
             for k in range(1, panels)]
    for ax in axes[:panels - columns]:
        ax.xaxis.set_tick_params(labelbottom=False)
    _title(figure, title, width)
    return figure, axes, columns


def _title(figure, title: str, width: float) -> None:
    """The figure's title, broken into lines that fit its width (inches), never clipped."""
    import textwrap

    fits = max(20, int(width * 72 / 7.5))  # characters of a 12-point title per line
    figure.suptitle("\n".join(textwrap.wrap(title, fits)), fontsize=12 if len(title) <= fits
                    else 10)


def _shared_legend(figure, axes) -> None:
    """One legend for the panels ``axes`` of ``figure`` (their labelled artists, each label
    once, in order), in one row under the title (:data:`LEGEND_ROW`): a fixed place costs
    nothing to find, where ``loc="best"`` tries every line of a panel against nine places, and
    it hides no curve."""
    handles = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, handle)
    figure.legend(list(handles.values()), list(handles), loc="center",
                  bbox_to_anchor=(0.5, 1 - 0.62 / figure.get_figheight()),
                  ncols=max(1, len(handles)), fontsize=8, frameon=False, columnspacing=1.5)


def _panel_title(ax, name: str) -> None:
    """A panel's title at a fixed height: left to itself matplotlib lays out the panel's tick
    labels once more to keep the title clear of them (a third of a sheet's drawing)."""
    ax.set_title(name, fontsize=9, y=1.0)


#: A panel whose largest value is below this fraction of its figure's largest is round-off.
ROUND_OFF = 1e-9


def _scale_round_off(axes, values: list[np.ndarray]) -> None:
    """Panels whose values are round-off (e.g. the moments of point contacts, 1e-15) drawn at
    the scale of the figure's largest panel, with a note, rather than auto-scaled into what
    would look like a signal."""
    peaks = [float(np.nanmax(np.abs(v))) if np.size(v) else 0.0 for v in values]
    largest = max(peaks, default=0.0)
    for ax, peak in zip(axes, peaks, strict=True):
        if largest > 0 and peak < ROUND_OFF * largest:
            ax.set_ylim(-largest, largest)
            ax.text(0.5, 0.62, f"round-off (below {ROUND_OFF:g} of the largest panel)",
                    transform=ax.transAxes, ha="center", va="center", fontsize=7,
                    color="0.35")


def _align_zeros(left, right) -> None:
    """Limits of two axes sharing a panel so that their zeros lie at the same height."""
    ranges = []
    for ax in (left, right):
        low, high = ax.get_ylim()
        ranges.append((min(low, 0.0), max(high, 0.0)))
    # the fraction of each axis below zero; both get the larger
    below = max(-low / (high - low) if high > low else 0.5 for low, high in ranges)
    below = min(max(below, 0.0), 1.0)
    for ax, (low, high) in zip((left, right), ranges, strict=True):
        if below >= 1.0:
            ax.set_ylim(low, 0.0)
        elif below <= 0.0:
            ax.set_ylim(0.0, high)
        else:
            span = max(high / (1 - below), -low / below)
            ax.set_ylim(-below * span, (1 - below) * span)


def _finish_panels(axes, columns: int) -> None:
    """Grid, ticks and the time label (on the lowest panel of each column) of :func:`_figure`'s
    panels, once their limits are final."""
    for k, ax in enumerate(axes):
        lowest = k >= len(axes) - columns
        if lowest:
            ax.set_xlabel("t (s)")
        light_ticks(ax, x_labels=lowest)


def png_bytes(figure: Figure, dpi: int = 110) -> bytes:
    """A :class:`matplotlib.figure.Figure` rendered as PNG bytes (at ``dpi`` dots per inch).

    The figure is drawn once by Agg and its opaque pixels encoded as RGB at zlib level 3:
    matplotlib's own ``savefig`` encodes RGBA at level 6, a sixth of a sheet's time for an
    alpha channel that is 255 everywhere on an opaque figure and some 5 % smaller files. A
    figure with a transparent background keeps its alpha channel.

    Parameters
    ----------
    figure : matplotlib.figure.Figure
    dpi : int
        Dots per inch.

    Returns
    -------
    bytes
        The PNG file's content.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    figure.set_dpi(dpi)
    canvas = FigureCanvasAgg(figure)
    canvas.draw()
    pixels = np.asarray(canvas.buffer_rgba())
    if (pixels[..., 3] == 255).all():
        pixels = pixels[..., :3]
    buffer = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(pixels)).save(
        buffer, format="png", compress_level=3, dpi=(dpi, dpi))
    return buffer.getvalue()


#: The builders a forked process renders (:func:`render_figures`): set before the fork, so the
#: children inherit them instead of receiving pickles.
_PENDING: list = []


def render_figures(builders: dict, workers: int = 1) -> dict[str, bytes]:
    """Each figure made by its builder and rendered as PNG bytes (:func:`png_bytes`), by name.

    Parameters
    ----------
    builders : dict of str to callable
        ``name -> build``, ``build()`` returning a :class:`matplotlib.figure.Figure`.
    workers : int
        Processes that share the figures: with more than one, on a system that forks (Linux)
        and from a process running no other thread, this process is forked that many times
        (the figures are independent; the bytes are those of one process). One draws them
        here.

    Returns
    -------
    dict of str to bytes
        The PNG files' contents, in the order of ``builders``.
    """
    names = list(builders)
    import threading

    # forking a process that runs other threads may copy a lock one of them holds
    if (workers <= 1 or len(names) < 2 or not sys.platform.startswith("linux")
            or threading.active_count() > 1):
        return {name: png_bytes(builders[name]()) for name in names}
    import multiprocessing
    import signal
    from concurrent.futures import ProcessPoolExecutor

    prepare_drawing()  # once, here: the forked processes inherit it
    global _PENDING
    _PENDING = [builders[name] for name in names]
    # an interruption is held while the processes are forked and draw (a few seconds): a
    # handler run inside the fork's own hooks would print a traceback, and the children would
    # be left to stop by themselves; it is raised here once they are done
    held = {signal.SIGINT, signal.SIGTERM}
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        with ProcessPoolExecutor(max_workers=min(workers, len(names)),
                                 mp_context=multiprocessing.get_context("fork")) as pool:
            return dict(zip(names, pool.map(_render_pending, range(len(names))), strict=True))
    finally:
        _PENDING = []
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


def prepare_drawing() -> None:
    """matplotlib's figure, its Agg canvas, Pillow and the default font loaded: what every
    process that draws pays first (0.5 s of CPU on a slow core), paid once by a process that
    forks its drawers rather than by each of them."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: F401
    from matplotlib.figure import Figure  # noqa: F401
    from matplotlib.font_manager import FontProperties, findfont, get_font
    from PIL import Image, PngImagePlugin  # noqa: F401

    get_font(findfont(FontProperties()))


def _render_pending(index: int) -> bytes:
    return png_bytes(_PENDING[index]())


def wrench_figure(times: np.ndarray, values: np.ndarray, names: list[str], symbol: str,
                  unit: str, title: str) -> Figure:
    """Components and magnitude of vectors ``values`` (N, panels, 3), e.g. every joint's force,
    against time: one panel per vector, titled by ``names``.

    Parameters
    ----------
    times : ndarray, shape (N,)
        s.
    values : ndarray, shape (N, panels, 3)
        The vectors, in ``unit``.
    names : list of str, length panels
        Each panel's title.
    symbol : str
        The vector's symbol in the legend (``F`` gives ``Fx, Fy, Fz, |F|``).
    unit : str
        The vertical axes' label, e.g. ``"N"``.
    title : str
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    figure, axes, columns = _figure(len(names), title, legend=True)
    for k, (ax, name) in enumerate(zip(axes, names, strict=True)):
        for c, colour in enumerate(COMPONENT_COLOURS):
            ax.plot(times, values[:, k, c], color=colour, linewidth=1.0,
                    label=f"{symbol}{'xyz'[c]}")
        ax.plot(times, np.linalg.norm(values[:, k], axis=1), color="black", linewidth=1.6,
                label=f"|{symbol}|")
        _panel_title(ax, name)
        ax.set_ylabel(unit, fontsize=8)
    _scale_round_off(axes, [values[:, k] for k in range(len(names))])
    _finish_panels(axes, columns)
    _shared_legend(figure, axes[:1])
    return figure


#: Colours of the legs in the figures that compare them (then dashed, then dotted, past ten).
LEG_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown",
               "tab:pink", "tab:gray", "tab:olive", "tab:cyan")


def leg_comparison_figure(times: np.ndarray, values: np.ndarray, legs: list[str],
                          panels: list[str], unit: str, title: str) -> Figure:
    """The legs side by side: one panel per joint of a leg (the k-th joint of every leg
    together), one line per leg.

    Parameters
    ----------
    times : ndarray, shape (N,)
        s.
    values : ndarray, shape (N, legs, panels)
        What is compared (a magnitude, an effort), in ``unit``; NaN where a leg has no such
        joint.
    legs, panels : list of str
        The legs' names (the legend) and the panels' titles.
    unit : str
        The vertical axes' label.
    title : str
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    figure, axes, columns = _figure(len(panels), title, legend=True)
    styles = ("-", "--", ":")
    for k, (ax, name) in enumerate(zip(axes, panels, strict=True)):
        for m, leg in enumerate(legs):
            ax.plot(times, values[:, m, k], color=LEG_COLOURS[m % len(LEG_COLOURS)],
                    linestyle=styles[m // len(LEG_COLOURS) % len(styles)], linewidth=1.1,
                    label=leg)
        _panel_title(ax, name)
        ax.set_ylabel(unit, fontsize=8)
    _scale_round_off(axes, [values[:, :, k] for k in range(len(panels))])
    _finish_panels(axes, columns)
    _shared_legend(figure, axes[:1])
    return figure


def effort_figure(times: np.ndarray, efforts: list[tuple[str, str, np.ndarray, np.ndarray]],
                  title: str) -> Figure:
    """Each actuator's effort (solid, left axis) and power (dashed, right axis) against time;
    ``efforts`` holds (name, unit of the effort, effort, power) per actuator.

    Parameters
    ----------
    times : ndarray, shape (N,)
        s.
    efforts : list of (str, str, ndarray, ndarray)
        Per actuator: its name, the effort's unit (``"N m"`` or ``"N"``), the effort (N,) and
        the power (N,), W.
    title : str
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    figure, axes, columns = _figure(len(efforts), title, twin=True)
    for ax, (name, unit, effort, power) in zip(axes, efforts, strict=True):
        ax.plot(times, effort, color="tab:blue", linewidth=1.3)
        ax.set_ylabel(f"effort ({unit})", fontsize=8, color="tab:blue")
        twin = ax.twinx()
        twin.plot(times, power, color="tab:orange", linewidth=1.0, linestyle="--")
        twin.set_ylabel("power (W)", fontsize=8, color="tab:orange")
        twin.tick_params(labelsize=8)
        few_ticks(twin, "y")
        _align_zeros(ax, twin)
        _panel_title(ax, name)
    _finish_panels(axes, columns)
    return figure


def trajectory_figure(times: np.ndarray, trajectories: dict[str, np.ndarray],
                      title: str) -> Figure:
    """Paths of points (e.g. the feet): side view (x, z), top view (x, y), and the coordinates
    against time; a dot marks each path's start.

    Parameters
    ----------
    times : ndarray, shape (N,)
        s.
    trajectories : dict of str to ndarray, shape (N, 3)
        World positions (m) by name, e.g. from :func:`hexapod.marker_trajectories`.
    title : str
        The figure's title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    width, height = 13.0, 4.2 + LEGEND_ROW
    figure = Figure(figsize=(width, height))
    side, top, timeline = figure.subplots(1, 3)
    figure.subplots_adjust(left=0.75 / width, right=1 - 0.2 / width, bottom=0.55 / height,
                           top=1 - (0.65 + LEGEND_ROW) / height, wspace=0.3)
    colours = [f"C{k % 10}" for k in range(len(trajectories))]
    for colour, (name, path) in zip(colours, trajectories.items(), strict=True):
        for ax, (i, j) in ((side, (0, 2)), (top, (0, 1))):
            ax.plot(path[:, i], path[:, j], color=colour, linewidth=1.3, label=name)
            ax.plot(path[0, i], path[0, j], "o", color=colour, markersize=4)
    for ax, (x, y), view in ((side, "xz", "side view"), (top, "xy", "top view")):
        ax.set_xlabel(f"{x} (m)")
        ax.set_ylabel(f"{y} (m)")
        ax.set_aspect("equal", adjustable="datalim")
        _panel_title(ax, view)
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
    _panel_title(timeline, "against time")
    for ax in (side, top, timeline):
        ax.apply_aspect()  # the views' limits as drawn (equal scales), final from here on
        light_ticks(ax)
    _shared_legend(figure, [timeline if len(trajectories) == 1 else top])
    _title(figure, title, figure.get_figwidth())
    return figure


# ------------------------------------------------------------------ a walking robot's feet

#: Shade of the stance intervals (grey, as in ground-reaction and gait diagrams).
STANCE_SHADE = "0.85"


def _leg_layout(legs: list[str]) -> tuple[int, int, list[tuple[int, int]]]:
    """Rows, columns and each leg's panel: a robot's ``L1 .. L3`` down the left column and
    ``R1 .. R3`` down the right, as the legs stand (front at the top); other names in a grid in
    their order."""
    places = []
    for leg in legs:
        side, number = leg[:1], leg[1:]
        if side not in ("L", "R") or not number.isdigit() or int(number) < 1:
            break
        places.append((int(number) - 1, 0 if side == "L" else 1))
    if len(places) == len(legs) and len(set(places)) == len(places) and places:
        return max(r for r, _ in places) + 1, 2, places
    columns = min(len(legs), max(1, math.ceil(math.sqrt(1.5 * len(legs)))))
    return (math.ceil(len(legs) / columns), columns,
            [(k // columns, k % columns) for k in range(len(legs))])


def _leg_panels(legs: list[str], title: str):
    """A figure with one panel per leg, placed by :func:`_leg_layout`, all sharing both axes,
    with room for a legend row under the title. Returns the figure, the panels in the order
    of ``legs``, and per panel whether it is the first and the last of its row (where the
    shared vertical axis is labelled, left and right) and the lowest of its column (where
    the time axis is)."""
    from matplotlib.figure import Figure

    rows, columns, places = _leg_layout(legs)
    width, height = 4.6 * columns + 0.6, 2.4 * rows + 1.0 + LEGEND_ROW
    figure = Figure(figsize=(width, height))
    grid = figure.add_gridspec(rows, columns, left=0.8 / width, right=1 - 0.8 / width,
                               bottom=0.55 / height, top=1 - (0.7 + LEGEND_ROW) / height,
                               wspace=0.35, hspace=0.4)
    axes = [figure.add_subplot(grid[places[0]])]
    axes += [figure.add_subplot(grid[place], sharex=axes[0], sharey=axes[0])
             for place in places[1:]]
    _title(figure, title, width)
    used = set(places)
    ends = []
    for ax, (r, c) in zip(axes, places, strict=True):
        row = [c2 for r2, c2 in places if r2 == r]
        ends.append((c == min(row), c == max(row), (r + 1, c) not in used))
        ax.tick_params(labelleft=ends[-1][0], labelbottom=ends[-1][2])
        if ends[-1][2]:
            ax.set_xlabel("t (s)")
    return figure, axes, ends


def _finish_leg_panels(axes, ends) -> None:
    """Grid and ticks of :func:`_leg_panels`' panels, once every panel is drawn (they share
    their limits)."""
    for ax, (first, _, lowest) in zip(axes, ends, strict=True):
        light_ticks(ax, x_labels=lowest, y_labels=first)


def _shade(ax, intervals) -> None:
    for start, stop in intervals:
        ax.axvspan(start, stop, color=STANCE_SHADE, linewidth=0, zorder=0)


def ground_reaction_figure(times: np.ndarray, forces: np.ndarray, legs: list[str],
                           stance: list, weight: float, title: str,
                           status: np.ndarray | None = None):
    """The ground's force on each foot against time, one panel per foot placed as the legs
    stand (left column ``L1 L2 L3``, right column ``R1 R2 R3``), as in the ground-reaction
    figures of cockroach locomotion (Full and Tu 1991): vertical (``GRz``), fore-aft (``GRx``)
    and lateral (``GRy``, to the left positive) components in N, stance shaded grey; a right
    axis in body weights when ``weight`` (N) is positive. ``forces`` (N, feet, 3), world axes;
    ``stance``: per foot, its (touch-down, lift-off) intervals; ``status`` (N, feet), where
    given: the samples where a foot slips or pulls are hatched red (infeasible)."""
    from hexapod.algorithms.ground import INFEASIBLE_STATUSES

    figure, axes, ends = _leg_panels(legs, title)
    for k, (ax, leg) in enumerate(zip(axes, legs, strict=True)):
        _shade(ax, stance[k])
        if status is not None:
            _hatch_infeasible(ax, times, np.isin(status[:, k], INFEASIBLE_STATUSES))
        ax.axhline(0.0, color="0.4", linewidth=0.6)
        ax.plot(times, forces[:, k, 2], color="black", linewidth=1.6, label="vertical (z)")
        ax.plot(times, forces[:, k, 0], color="tab:red", linewidth=1.1, label="fore-aft (x)")
        ax.plot(times, forces[:, k, 1], color="tab:blue", linewidth=1.1,
                label="lateral (y, left +)")
        _panel_title(ax, leg)
        if ends[k][0]:
            ax.set_ylabel("N", fontsize=8)
    _finish_leg_panels(axes, ends)
    for ax, (_, last, _) in zip(axes, ends, strict=True):
        # the panels share their scale: body weights on the right of each row
        if weight > 0 and last and not light_scale(ax, 1.0 / weight, "body weights"):
            right = ax.secondary_yaxis("right", functions=(lambda f: f / weight,
                                                           lambda b: b * weight))
            right.set_ylabel("body weights", fontsize=8)
            right.tick_params(labelsize=8)
            few_ticks(right, "y")
    _shared_legend(figure, axes)
    return figure


def _hatch_infeasible(ax, times: np.ndarray, bad: np.ndarray) -> None:
    """Hatch each run of infeasible samples, from half a spacing before it to half after."""
    if not bad.any():
        return
    edges = np.concatenate([[times[0]], (times[1:] + times[:-1]) / 2, [times[-1]]])
    starts = np.flatnonzero(bad & ~np.concatenate([[False], bad[:-1]]))
    stops = np.flatnonzero(bad & ~np.concatenate([bad[1:], [False]]))
    for first, last in zip(starts, stops, strict=True):
        ax.axvspan(edges[first], edges[last + 1], facecolor="none", edgecolor="tab:red",
                   hatch="///", linewidth=0, zorder=0.5, label=None if first != starts[0]
                   else "infeasible (slip / pull)")


def friction_ratio_figure(times: np.ndarray, ratio: np.ndarray, status: np.ndarray,
                          legs: list[str], stance: list, mu: float, title: str):
    """Each foot's friction ratio ``|F_t| / (mu F_n)`` against time, one panel per foot placed
    as the legs stand, with the line ratio = 1 (the edge of the friction cone), stance shaded
    grey; samples where the policy says ``slip`` or ``pull`` marked with a red cross.
    ``ratio`` (N, feet) is NaN where a foot carries nothing; ``status`` (N, feet)."""
    from hexapod.algorithms.ground import INFEASIBLE_STATUSES

    figure, axes, ends = _leg_panels(legs, title)
    finite = ratio[np.isfinite(ratio)]
    top = max(1.25, min(1.05 * float(finite.max()), 5.0)) if finite.size else 1.25
    for k, (ax, leg) in enumerate(zip(axes, legs, strict=True)):
        _shade(ax, stance[k])
        ax.axhline(1.0, color="tab:red", linestyle="--", linewidth=1.0, label="ratio = 1")
        shown = np.where(np.isinf(ratio[:, k]), top, ratio[:, k])
        ax.plot(times, shown, color="black", linewidth=1.3, label="|F_t| / (mu F_n)")
        bad = np.isin(status[:, k], INFEASIBLE_STATUSES)
        if bad.any():
            ax.plot(times[bad], np.minimum(np.nan_to_num(shown[bad], nan=top), top), "x",
                    color="tab:red", markersize=6, label="slip / pull")
        ax.set_ylim(0.0, top)
        _panel_title(ax, leg)
        if ends[k][0]:
            ax.set_ylabel("friction ratio", fontsize=8)
    _finish_leg_panels(axes, ends)
    _shared_legend(figure, axes)
    figure.text(0.5, 0.005, f"mu = {mu:g}; above the dashed line the foot needs more friction "
                "than mu", ha="center", va="bottom", fontsize=8)
    return figure


def gait_diagram_figure(legs: list[str], stance: list, start: float, stop: float, title: str,
                        scheduled: list | None = None):
    """The gait diagram: one row per leg (in ``legs``' order, the first at the top), a black
    bar over each stance, as in insect gait diagrams; with ``scheduled`` (intervals per leg),
    the schedule's stances as wider grey bars behind them."""
    from matplotlib.figure import Figure

    width, height = 8.0, 0.45 * len(legs) + 1.3
    figure = Figure(figsize=(width, height))
    ax = figure.subplots()
    # room for the longest row label (some 0.085 inch a character at 10 points)
    left = max(0.8, 0.25 + 0.085 * max((len(leg) for leg in legs), default=0))
    figure.subplots_adjust(left=left / width, right=1 - 0.25 / width, bottom=0.55 / height,
                           top=1 - 0.45 / height)
    for row, intervals in enumerate(stance):
        y = len(legs) - 1 - row
        if scheduled is not None:
            ax.broken_barh([(a, b - a) for a, b in scheduled[row]], (y - 0.4, 0.8),
                           facecolors="0.75", label="scheduled" if row == 0 else None)
        ax.broken_barh([(a, b - a) for a, b in intervals],
                       (y - 0.2, 0.4) if scheduled is not None else (y - 0.35, 0.7),
                       facecolors="black", label="simulated" if row == 0 else None)
    if scheduled is not None:  # in the bottom right corner, beside the axis' label (a long
        # title reaches the top right corner)
        figure.legend(loc="lower right", bbox_to_anchor=(1 - 0.1 / width, 0.02), fontsize=7,
                      ncols=2, frameon=False, borderaxespad=0.1)
    ax.set_yticks(range(len(legs)), list(reversed(legs)))
    ax.set_ylim(-0.6, len(legs) - 0.4)
    ax.set_xlim(start, stop)
    ax.set_xlabel("t (s)")
    ax.grid(True, axis="x", linewidth=0.4, alpha=0.6)
    ax.set_title(title, fontsize=10, y=1.0)
    few_ticks(ax, "x")
    return figure
