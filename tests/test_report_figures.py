"""The report's figures read right: twin axes share their zero, round-off panels are not drawn
as signals, titles are never clipped, and a robot's joints are grouped by limb whatever their
names."""

from __future__ import annotations

from pathlib import Path

import numpy as np

import hexapod as hx
from hexapod.output.figures import ROUND_OFF, effort_figure, png_bytes, wrench_figure
from hexapod.output.ground import leg_groups
from hexapod.scene.urdf import read_urdf

TIMES = np.linspace(0.0, 1.0, 50)


def test_effort_and_power_axes_share_their_zero():
    effort = 3.0 + 2.0 * np.sin(2 * np.pi * TIMES)  # mostly positive
    power = -40.0 + 60.0 * np.cos(2 * np.pi * TIMES)  # mostly negative
    figure = effort_figure(TIMES, [("knee", "N m", effort, power)], "efforts")
    left, right = figure.axes[0], figure.axes[-1]
    heights = [(0.0 - low) / (high - low) for low, high in (left.get_ylim(), right.get_ylim())]
    assert abs(heights[0] - heights[1]) < 1e-12
    assert left.get_ylim()[1] >= effort.max() and right.get_ylim()[0] <= power.min()


def test_a_round_off_panel_is_drawn_at_the_figures_scale_with_a_note():
    values = np.zeros((TIMES.size, 2, 3))
    values[:, 0, 2] = 80.0 * np.sin(TIMES)
    values[:, 1] = 1e-15 * np.cos(TIMES)[:, None]  # a point contact's moment
    figure = wrench_figure(TIMES, values, ["knee", "foot"], "T", "N m", "moments")
    low, high = figure.axes[1].get_ylim()
    assert high >= np.abs(values).max() and low <= -np.abs(values).max()
    assert any(f"round-off (below {ROUND_OFF:g}" in text.get_text()
               for text in figure.axes[1].texts)


def test_a_long_title_is_wrapped_inside_the_figure():
    title = "a robot with a long name: " + "joint forces, by parent on child " * 6
    figure = wrench_figure(TIMES, np.ones((TIMES.size, 1, 3)), ["knee"], "F", "N", title)
    png_bytes(figure)  # lays the text out
    from matplotlib.text import Text

    (shown,) = [t for t in figure.findobj(Text) if t.get_text() == figure.get_suptitle()]
    box = shown.get_window_extent()
    assert "\n" in shown.get_text()
    assert box.x0 >= 0 and box.x1 <= figure.bbox.width and box.y1 <= figure.bbox.height


def quadruped(path: Path) -> Path:
    """Four legs of three joints named FL_hip ... HR_calf on a 5 kg trunk."""
    inertia = '<inertia ixx="{0}" iyy="{0}" izz="{1}" ixy="0" ixz="0" iyz="0"/>'
    links, joints = [], []
    for leg, (x, y) in zip(("FL", "FR", "HL", "HR"),
                           ((0.2, 0.1), (0.2, -0.1), (-0.2, 0.1), (-0.2, -0.1)), strict=True):
        parent = "trunk"
        for part, axis, origin in (("hip", "1 0 0", f"{x} {y} 0"), ("thigh", "0 1 0", "0 0 0"),
                                   ("calf", "0 1 0", "0 0 -0.2")):
            links.append(f'<link name="{leg}_{part}_link"><inertial><origin xyz="0 0 -0.1"/>'
                         f'<mass value="0.5"/>{inertia.format(0.002, 0.001)}</inertial></link>')
            joints.append(f'<joint name="{leg}_{part}" type="revolute"><parent link="{parent}"/>'
                          f'<child link="{leg}_{part}_link"/><origin xyz="{origin}"/>'
                          f'<axis xyz="{axis}"/></joint>')
            parent = f"{leg}_{part}_link"
    path.write_text(f'<robot name="q"><link name="trunk"><inertial><mass value="5"/>'
                    f'{inertia.format(0.05, 0.08)}</inertial></link>{"".join(links)}'
                    f'{"".join(joints)}</robot>')
    return path


def test_a_urdf_robots_joints_are_grouped_by_limb(tmp_path):
    model = hx.assemble(read_urdf(quadruped(tmp_path / "q.urdf"), base="fixed"))
    names = [j.name for j in model.joints]
    groups = leg_groups(names, model)
    assert list(groups) == ["FL", "FR", "HL", "HR", "other"]
    for leg in ("FL", "FR", "HL", "HR"):
        assert [names[k] for k in groups[leg]] == [f"{leg}_{p}" for p in ("hip", "thigh", "calf")]
    assert [names[k] for k in groups["other"]] == ["trunk/ground"]
    assert leg_groups(names) is None  # by the names alone: no L1/... prefixes


def test_figures_drawn_by_forked_processes_are_the_same_bytes():
    """render_figures shares the figures among forked processes (on Linux): the same PNG files
    as drawn here, in the builders' order."""
    from functools import partial

    from hexapod.output.figures import render_figures

    values = np.random.default_rng(3).normal(size=(TIMES.size, 2, 3)).cumsum(axis=0)
    builders = {f"sheet-{k}.png": partial(wrench_figure, TIMES, values * (k + 1), ["a", "b"],
                                          "F", "N", f"sheet {k}") for k in range(3)}
    here = render_figures(builders, workers=1)
    shared = render_figures(builders, workers=2)
    assert list(shared) == list(builders) and shared == here
    assert all(data.startswith(b"\x89PNG") for data in here.values())
