"""The report panels' own ticks read as matplotlib's would: a label at each grid line giving its
value, the axis labels clear of the tick labels, matplotlib's ticks kept where a label would
need a power of ten."""

from __future__ import annotations

import numpy as np
import pytest

from hexapod.output.figures import png_bytes
from hexapod.output.panel_axes import light_ticks, nice_ticks, tick_texts

MINUS = "\N{MINUS SIGN}"


@pytest.mark.parametrize(("ticks", "texts"), [
    ([0.0, 0.15, 0.3, 0.45], ["0.00", "0.15", "0.30", "0.45"]),
    ([-40.0, -20.0, 0.0, 20.0, 40.0], [f"{MINUS}40", f"{MINUS}20", "0", "20", "40"]),
    ([-0.3, 0.0, 0.3, 0.6], [f"{MINUS}0.3", "0.0", "0.3", "0.6"]),
    ([0.0, 0.25, 0.5, 0.75, 1.0, 1.25], ["0.00", "0.25", "0.50", "0.75", "1.00", "1.25"]),
])
def test_tick_labels_have_the_decimals_of_their_step(ticks, texts):
    assert tick_texts(np.array(ticks)) == texts


def test_labels_that_need_a_power_of_ten_are_left_to_matplotlib():
    assert tick_texts(np.array([0.0, 1e5, 2e5])) is None
    assert tick_texts(np.array([0.0, 2e-4, 4e-4])) is None


def panel(values: np.ndarray):
    from matplotlib.figure import Figure

    figure = Figure(figsize=(4.0, 3.0))
    ax = figure.add_subplot()
    figure.subplots_adjust(left=0.25, bottom=0.2)  # room for the labels, as the report's
    ax.plot(np.linspace(0.0, 0.5, values.size), values)
    ax.set_xlabel("t (s)")
    ax.set_ylabel("N")
    return figure, ax


@pytest.mark.parametrize("scale", [1.0, -1234.5, 0.01])
def test_each_label_stands_at_its_grid_line_and_the_axis_labels_clear_them(scale):
    from matplotlib.collections import LineCollection

    values = scale * np.sin(np.linspace(0.0, 6.0, 200))
    figure, ax = panel(values)
    light_ticks(ax)
    png_bytes(figure)  # lays the text out
    grids = [c for c in ax.collections if isinstance(c, LineCollection)]
    renderer = figure.canvas.get_renderer()
    for axis, index in (("x", 0), ("y", 1)):
        low, high = sorted(getattr(ax, f"get_{axis}lim")())
        expected = nice_ticks(low, high)
        assert 3 <= expected.size <= 6
        drawn = [seg[0][index] for c in grids for seg in c.get_segments()
                 if seg[0][index] == seg[1][index]]  # grid lines and marks across this axis
        assert sorted(set(drawn)) == pytest.approx(sorted(expected))
        # x labels hang centred under their line, y labels end left of theirs
        labels = [t for t in ax.texts if t.get_horizontalalignment() == (
            "center" if axis == "x" else "right")]
        assert sorted(t.get_position()[index] for t in labels) == pytest.approx(
            sorted(expected))
        for text in labels:
            assert float(text.get_text().replace(MINUS, "-")) == pytest.approx(
                text.get_position()[index], abs=1e-9 * np.ptp(expected))
        label = (ax.xaxis if axis == "x" else ax.yaxis).label.get_window_extent(renderer)
        for text in labels:
            assert not label.overlaps(text.get_window_extent(renderer)), (axis, text)
        inside = figure.bbox
        assert label.x0 >= 0 and label.y0 >= 0 and label.x1 <= inside.x1


def test_an_axis_beyond_plain_numbers_keeps_matplotlibs_ticks():
    figure, ax = panel(3e6 * np.linspace(0.0, 1.0, 50))
    light_ticks(ax)
    png_bytes(figure)
    assert len(ax.get_yticks()) > 0  # matplotlib's, with its offset or power of ten
    assert len(ax.get_xticks()) == 0  # time: plain, drawn here


def test_a_right_hand_scale_reads_the_values_times_its_factor():
    from matplotlib.collections import LineCollection

    from hexapod.output.panel_axes import light_scale

    weight = 196.2  # N: labels in body weights
    figure, ax = panel(120.0 * np.sin(np.linspace(0.0, 6.0, 200)))
    light_ticks(ax)
    assert light_scale(ax, 1.0 / weight, "body weights")
    png_bytes(figure)
    right = [t for t in ax.texts if t.get_horizontalalignment() == "left"
             and t.get_rotation() == 0]
    low, high = sorted(v / weight for v in ax.get_ylim())
    assert sorted(float(t.get_text().replace(MINUS, "-")) for t in right) == pytest.approx(
        sorted(nice_ticks(low, high)))
    for text in right:  # each at the height of its value in newtons
        assert text.get_position()[1] == pytest.approx(
            float(text.get_text().replace(MINUS, "-")) * weight)
    marks = [c for c in ax.collections if isinstance(c, LineCollection)
             and all(seg[0][0] == 1.0 for seg in c.get_segments())]
    assert len(marks) == 1 and len(marks[0].get_segments()) == len(right)
    (label,) = [t for t in ax.texts if t.get_text() == "body weights"]
    renderer = figure.canvas.get_renderer()
    box = label.get_window_extent(renderer)
    assert all(not box.overlaps(t.get_window_extent(renderer)) for t in right)
    assert not light_scale(ax, 1e6, "micro")  # labels past plain numbers: not drawn here
