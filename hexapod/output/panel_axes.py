"""The grid, ticks and tick labels of the report's many small panels, drawn cheaply.

matplotlib makes every tick of every axis as five artists (two marks, a grid line, two labels),
anew for each axis and before its first drawing: on a sheet of seven panels that is half of the
drawing. :func:`light_ticks` draws the same grid lines, tick marks and labels as two line
collections and one text per label; :func:`few_ticks` is the fallback with matplotlib's ticks
(fewer of them) where a label would need matplotlib's offset or scientific notation.
"""

from __future__ import annotations

import functools

import numpy as np

#: Tick marks per panel axis at most (five instead of matplotlib's eight or nine).
TICKS = 5

#: matplotlib's look of ticks and grid: tick length and label pad (points), grid colour, width
#: and alpha (the report's lighter grid), tick label size (points).
TICK_LENGTH, TICK_PAD = 3.5, 3.5
GRID = {"colors": "#b0b0b0", "linewidths": 0.4, "alpha": 0.6}
LABEL_SIZE = 8

#: Advance widths of DejaVu Sans (matplotlib's default font), in ems, of the characters of tick
#: labels: where a panel's vertical label goes, without laying the labels out to measure them.
_ADVANCE = {**dict.fromkeys("0123456789", 0.636), ".": 0.318, "\N{MINUS SIGN}": 0.838}

#: Labels are written plainly between these magnitudes; past them matplotlib's ticks are used
#: (offsets, powers of ten).
_PLAIN = (1e-3, 1e5)


def grid_and_labels(ax) -> None:
    """A light grid and small tick labels on matplotlib's ticks, set in one pass over them
    (each of ``grid`` and ``tick_params`` is a pass over every tick of both axes)."""
    ax.tick_params(labelsize=LABEL_SIZE, gridOn=True, grid_color=GRID["colors"],
                   grid_linewidth=GRID["linewidths"], grid_alpha=GRID["alpha"])


def few_ticks(ax, which: str = "xy") -> None:
    """At most :data:`TICKS` of matplotlib's ticks on the axes ``which`` of ``ax``, only those
    in view (:func:`_in_view_locator`)."""
    locator = _in_view_locator()
    for axis in which:
        getattr(ax, f"{axis}axis").set_major_locator(locator(TICKS))


@functools.cache
def _in_view_locator():
    """matplotlib's ``MaxNLocator`` less the ticks outside the axis' limits: it returns one
    more on each side, which matplotlib makes (a tenth of a sheet's time) but never draws."""
    from matplotlib.ticker import MaxNLocator

    class InView(MaxNLocator):
        def __call__(self):
            return _within(super().__call__(), *sorted(self.axis.get_view_interval()))

    return InView


def nice_ticks(low: float, high: float) -> np.ndarray:
    """matplotlib's choice of at most :data:`TICKS` round values, those within [low, high]."""
    from matplotlib.ticker import MaxNLocator

    return _within(MaxNLocator(TICKS).tick_values(low, high), low, high)


def _within(ticks: np.ndarray, low: float, high: float) -> np.ndarray:
    """The ``ticks`` within ``[low, high]`` (a billionth of the span's slack for round-off)."""
    slack = 1e-9 * abs(high - low)
    return ticks[(ticks >= low - slack) & (ticks <= high + slack)]


def tick_texts(ticks: np.ndarray) -> list[str] | None:
    """The labels of evenly spaced ``ticks``, with as many decimals as the step needs and
    matplotlib's minus sign; ``None`` when a label would need an offset or a power of ten."""
    if ticks.size == 0:
        return []
    largest = float(np.abs(ticks).max())
    step = float(np.diff(ticks).min()) if ticks.size > 1 else largest
    if largest >= _PLAIN[1] or (step > 0 and step < _PLAIN[0]):
        return None
    digits = next((d for d in range(8)
                   if np.all(np.abs(ticks - np.round(ticks, d)) <= 1e-6 * max(step, 1e-300))),
                  8)
    out = []
    for value in ticks:
        text = f"{0.0 if abs(value) <= 1e-9 * max(step, 1e-300) else value:.{digits}f}"
        out.append(text.replace("-", "\N{MINUS SIGN}"))
    return out


def _width_points(text: str) -> float:
    return LABEL_SIZE * sum(_ADVANCE.get(c, 0.65) for c in text)


def light_ticks(ax, x_labels: bool = True, y_labels: bool = True) -> None:
    """The grid, outward tick marks and tick labels of panel ``ax`` at the round values within
    its limits as they are now (fixed from here on), as matplotlib draws them, in a few
    artists; the axis labels placed beyond the tick labels. ``x_labels``, ``y_labels``: whether
    the tick labels of that axis are written (a panel sharing the other's axis leaves them).
    An axis whose labels would need an offset or a power of ten keeps matplotlib's ticks
    (:func:`few_ticks`). Call it once the panel's limits are final (data drawn, limits set);
    panels sharing an axis must all take it or all not (they share its ticks)."""
    from matplotlib.collections import LineCollection
    from matplotlib.transforms import ScaledTranslation

    figure = ax.get_figure()
    box = ax.get_position()
    size = (box.width * figure.get_figwidth() * 72, box.height * figure.get_figheight() * 72)
    limits = {"x": ax.get_xlim(), "y": ax.get_ylim()}  # autoscaled now, if they were to be
    # frozen (set_xlim would do it too, but it sets every panel sharing the axis: n^2 on a sheet)
    ax.set_autoscale_on(False)
    label_room = {"x": TICK_LENGTH + TICK_PAD, "y": TICK_LENGTH + TICK_PAD}
    light = set()
    for axis in "xy":
        ticks = nice_ticks(*sorted(limits[axis]))
        texts = tick_texts(ticks)
        if texts is None:
            grid_and_labels(ax)
            few_ticks(ax, axis)
            continue
        getattr(ax, f"set_{axis}ticks")([])
        light.add(axis)
        transform = ax.get_xaxis_transform() if axis == "x" else ax.get_yaxis_transform()
        mark = TICK_LENGTH / size[1 if axis == "x" else 0]  # in axes fractions
        lines = [((t, 0.0), (t, 1.0)) for t in ticks]
        marks = [((t, 0.0), (t, -mark)) for t in ticks]
        if axis == "y":
            lines = [(a[::-1], b[::-1]) for a, b in lines]
            marks = [(a[::-1], b[::-1]) for a, b in marks]
        ax.add_collection(LineCollection(lines, transform=transform, zorder=1.5, **GRID),
                          autolim=False)
        ax.add_collection(LineCollection(marks, transform=transform, colors="black",
                                         linewidths=0.8, clip_on=False, zorder=2.5),
                          autolim=False)
        if not (x_labels if axis == "x" else y_labels):
            continue
        gap = (TICK_LENGTH + TICK_PAD) / 72
        if axis == "x":
            shift = ScaledTranslation(0.0, -gap, figure.dpi_scale_trans)
            for t, text in zip(ticks, texts, strict=True):
                ax.text(t, 0.0, text, transform=transform + shift, ha="center", va="top",
                        fontsize=LABEL_SIZE)
            label_room["x"] += 1.25 * LABEL_SIZE
        else:
            shift = ScaledTranslation(-gap, 0.0, figure.dpi_scale_trans)
            for t, text in zip(ticks, texts, strict=True):
                ax.text(0.0, t, text, transform=transform + shift, ha="right",
                        va="center_baseline", fontsize=LABEL_SIZE)
            label_room["y"] += max(map(_width_points, texts), default=0.0)
    # the axis labels beyond the tick labels, plus matplotlib's label pad (4 pt), where
    # matplotlib would put them after measuring its tick labels
    if "x" in light:
        ax.xaxis.set_label_coords(0.5, -(label_room["x"] + 4.0) / size[1])
    if "y" in light:
        ax.yaxis.set_label_coords(-(label_room["y"] + 4.0) / size[0], 0.5)


def light_scale(ax, scale: float, label: str) -> bool:
    """A right-hand scale on panel ``ax`` reading its vertical values times ``scale`` (> 0;
    e.g. newtons in body weights): tick marks and labels at round values of the scale and
    the ``label``, drawn as :func:`light_ticks` draws a panel's own (matplotlib's secondary
    axis is a whole Axes with its ticks: a third of a ground figure). Call it once the limits
    are final. False, with nothing drawn, when the labels would need a power of ten (then use
    ``ax.secondary_yaxis``)."""
    from matplotlib.collections import LineCollection
    from matplotlib.transforms import ScaledTranslation

    low, high = sorted(scale * v for v in ax.get_ylim())
    ticks = nice_ticks(low, high)
    texts = tick_texts(ticks)
    if texts is None or scale <= 0:
        return False
    figure = ax.get_figure()
    width = ax.get_position().width * figure.get_figwidth() * 72
    transform = ax.get_yaxis_transform()
    mark = TICK_LENGTH / width
    ax.add_collection(LineCollection([((1.0, t / scale), (1.0 + mark, t / scale)) for t in ticks],
                                     transform=transform, colors="black", linewidths=0.8,
                                     clip_on=False, zorder=2.5), autolim=False)
    gap = (TICK_LENGTH + TICK_PAD) / 72
    shift = ScaledTranslation(gap, 0.0, figure.dpi_scale_trans)
    for t, text in zip(ticks, texts, strict=True):
        ax.text(1.0, t / scale, text, transform=transform + shift, ha="left",
                va="center_baseline", fontsize=LABEL_SIZE)
    room = (TICK_LENGTH + TICK_PAD + max(map(_width_points, texts)) + 4.0) / 72
    ax.text(1.0, 0.5, label, transform=ax.transAxes + ScaledTranslation(
        room, 0.0, figure.dpi_scale_trans), rotation=90, ha="left", va="center",
        fontsize=LABEL_SIZE)
    return True
