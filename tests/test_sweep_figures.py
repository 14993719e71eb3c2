"""The figures of a design sweep (``hexapod.output.sweep_figures``) on small synthetic tables: one
numeric parameter, one categorical, two numeric on a grid, two numeric sampled at random, each
with a failed case and NaN values. The expected numbers are computed here from the table, apart
from the module, and compared with the data the figures hold."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np
import pytest

from hexapod.output.figures import png_bytes
from hexapod.output.sweep_figures import metric_families, sweep_figures

JOINTS = [f"{side}{k}/{joint}" for side in "LR" for k in (1, 2, 3)
          for joint in ("coxa_rot", "cti", "tita")]
FEET = [f"{side}{k}" for side in "LR" for k in (1, 2, 3)]
SAFE = re.compile(r"[A-Za-z0-9_.-]+")


def table(parameters: dict[str, np.ndarray], failed: int, seed: int = 0):
    """A table over the cases of ``parameters``: 18 joint efforts, 6 feet's friction ratios and
    the energy, random; case ``failed`` failed (NaN everywhere), one foot's ratio NaN in case 0
    and the energy NaN in case 1."""
    cases = len(next(iter(parameters.values())))
    rng = np.random.default_rng(seed)
    metrics = {f"peak_effort:{j}": rng.uniform(0.1, 2.0, cases) for j in JOINTS}
    metrics |= {f"friction_ratio:{f}": rng.uniform(0.0, 1.2, cases) for f in FEET}
    metrics["energy"] = rng.uniform(1.0, 5.0, cases)
    metrics["friction_ratio:L2"][0] = np.nan
    metrics["energy"][1] = np.nan
    for values in metrics.values():
        values[failed] = np.nan
    units = {name: ("N m" if name.startswith("peak") else "J" if name == "energy" else "")
             for name in metrics}
    units |= {"duty": "", "speed": "m/s", "gait": "", "step height": "m"}
    status = np.array(["ok"] * cases, dtype=object)
    status[failed] = "failed"
    return parameters, metrics, units, status


@pytest.fixture(scope="module")
def grid():
    duty = np.repeat([0.5, 0.6, 0.75], 4)
    speed = np.tile([0.05, 0.1, 0.2, 0.3], 3)
    parameters, metrics, units, status = table({"duty": duty, "speed": speed}, failed=6)
    return (parameters, metrics, units, status,
            dict(sweep_figures(parameters, metrics, units, status, "grid study")))


@pytest.fixture(scope="module")
def random_pair():
    rng = np.random.default_rng(7)
    parameters = {"duty": rng.uniform(0.5, 0.8, 15), "speed": rng.uniform(0.05, 0.3, 15)}
    parameters, metrics, units, status = table(parameters, failed=3, seed=1)
    return (parameters, metrics, units, status,
            dict(sweep_figures(parameters, metrics, units, status, "random study")))


def line(ax, gid: str):
    (found,) = [artist for artist in ax.lines if artist.get_gid() == gid]
    return found


def family_max(metrics, family: str, status) -> np.ndarray:
    columns = [np.asarray(v, float) for k, v in metrics.items() if k.split(":")[0] == family]
    stacked = np.column_stack(columns)
    out = np.array([np.max(row[~np.isnan(row)]) if (~np.isnan(row)).any() else np.nan
                    for row in stacked])
    return np.where(np.asarray(status) == "ok", out, np.nan)


def test_metric_families_keep_their_order():
    names = ["peak_effort:L1/tita", "energy", "peak_effort:R3/coxa_rot", "peak_ground:L1",
             "cost_of_transport", "peak_ground:R2"]
    assert metric_families(names) == {
        "peak_effort": ["peak_effort:L1/tita", "peak_effort:R3/coxa_rot"],
        "energy": ["energy"],
        "peak_ground": ["peak_ground:L1", "peak_ground:R2"],
        "cost_of_transport": ["cost_of_transport"]}
    assert metric_families([]) == {}


def test_one_numeric_parameter():
    """Names; the scalar's line is its values (failed case a gap), the failed case is counted in
    the title and marked; the 18 joints show the 6 largest, the largest first."""
    speed = np.array([0.05, 0.1, 0.15, 0.2, 0.25])
    parameters, metrics, units, status = table({"speed": speed}, failed=2)
    figures = dict(sweep_figures(parameters, metrics, units, status, "speed study"))
    assert list(figures) == ["peak_effort-vs-speed.png", "friction_ratio-vs-speed.png",
                             "energy-vs-speed.png"]
    ax = figures["energy-vs-speed.png"].axes[0]
    np.testing.assert_array_equal(line(ax, "energy").get_xdata(), speed)
    np.testing.assert_array_equal(line(ax, "energy").get_ydata(), metrics["energy"])
    assert ax.get_xlabel() == "speed [m/s]" and ax.get_ylabel() == "energy [J]"
    assert "1 of 5 cases not ok" in figures["energy-vs-speed.png"]._suptitle.get_text()
    np.testing.assert_array_equal(line(ax, "failed").get_xdata(), [0.15])
    legend = [t.get_text() for t in figures["peak_effort-vs-speed.png"].axes[0]
              .get_legend().get_texts()]
    peaks = {j: np.nanmax(metrics[f"peak_effort:{j}"]) for j in JOINTS}
    assert legend[:6] == sorted(peaks, key=peaks.get, reverse=True)[:6]
    assert legend[6:] == ["12 others", "failed (1)"]


def test_categorical_parameter():
    gait = np.array(["tripod", "wave", "tripod", "tetrapod", "wave", "tetrapod"])
    parameters, metrics, units, status = table({"gait": gait}, failed=4)
    figures = dict(sweep_figures(parameters, metrics, units, status, "gait study"))
    assert list(figures) == ["peak_effort-vs-gait.png", "friction_ratio-vs-gait.png",
                             "energy-vs-gait.png"]
    ax = figures["energy-vs-gait.png"].axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["tripod", "wave", "tetrapod"]
    energy = line(ax, "energy")
    np.testing.assert_array_equal(energy.get_xdata(), [0, 1, 2])
    # wave: one case failed, the other has no energy, so no point
    expected = [max(metrics["energy"][gait == "tripod"]), np.nan,
                max(metrics["energy"][gait == "tetrapod"])]
    np.testing.assert_array_equal(energy.get_ydata(), expected)
    assert energy.get_linestyle() == "None"
    np.testing.assert_array_equal(line(ax, "failed").get_xdata(), [1])


def test_grid_names_and_envelope(grid):
    parameters, metrics, _, status, figures = grid
    assert list(figures) == [
        "peak_effort-vs-duty.png", "peak_effort-vs-speed.png", "peak_effort-map.png",
        "friction_ratio-vs-duty.png", "friction_ratio-vs-speed.png", "friction_ratio-map.png",
        "energy-vs-duty.png", "energy-vs-speed.png", "energy-map.png"]
    ax = figures["peak_effort-vs-duty.png"].axes[0]
    assert "max over speed" in ax.get_ylabel()
    duty = parameters["duty"]
    for joint in JOINTS:
        values = np.where(status == "ok", metrics[f"peak_effort:{joint}"], np.nan)
        expected = [np.nanmax(values[duty == d]) for d in (0.5, 0.6, 0.75)]
        np.testing.assert_array_equal(line(ax, joint).get_ydata(), expected)
    ax = figures["energy-vs-speed.png"].axes[0]
    speed = parameters["speed"]
    expected = [np.nanmax(metrics["energy"][speed == s]) for s in (0.05, 0.1, 0.2, 0.3)]
    np.testing.assert_array_equal(line(ax, "energy").get_ydata(), expected)


@pytest.mark.parametrize("family", ["peak_effort", "friction_ratio", "energy"])
def test_heat_map_holds_the_family_maximum(grid, family):
    """Rows: speed, columns: duty; the failed case (duty 0.6, speed 0.2) and the case without
    energy (duty 0.5, speed 0.1) stay NaN; the element attaining the maximum is written."""
    parameters, metrics, units, status, figures = grid
    ax = figures[f"{family}-map.png"].axes[0]
    shown = ax.images[0].get_array()
    data = np.ma.filled(shown.astype(float), np.nan)
    expected = family_max(metrics, family, status).reshape(3, 4).T
    np.testing.assert_array_equal(data, expected)
    assert np.isnan(data[2, 1]) and bool(np.ma.getmaskarray(shown)[2, 1])
    assert np.isnan(data[1, 0]) == (family == "energy")
    assert ax.get_xlabel() == "duty" and ax.get_ylabel() == "speed [m/s]"
    texts = [t.get_text() for t in ax.texts]
    assert len(texts) == 12 and "failed" in texts
    if family == "peak_effort":
        stacked = np.column_stack([metrics[f"peak_effort:{j}"] for j in JOINTS])
        best = JOINTS[int(np.nanargmax(stacked[0]))]  # duty 0.5, speed 0.05: row 0, column 0
        (cell,) = [t for t in ax.texts if t.get_position() == (0, 0)]
        assert cell.get_text().startswith(best + "\n")
    label = figures[f"{family}-map.png"].axes[1].get_ylabel()
    assert label == {"peak_effort": "max peak_effort [N m]", "friction_ratio": "max friction_ratio",
                     "energy": "energy [J]"}[family]


def test_random_pair_draws_a_scatter(random_pair):
    parameters, metrics, units, status, figures = random_pair
    assert list(figures)[2::3] == ["peak_effort-map.png", "friction_ratio-map.png",
                                   "energy-map.png"]
    ax = figures["peak_effort-map.png"].axes[0]
    assert not ax.images
    expected = family_max(metrics, "peak_effort", status)
    points = ax.collections[0]
    np.testing.assert_array_equal(points.get_array(), expected[~np.isnan(expected)])
    np.testing.assert_array_equal(points.get_offsets()[:, 0],
                                  parameters["duty"][~np.isnan(expected)])
    ax = figures["energy-map.png"].axes[0]
    assert len(ax.collections[0].get_array()) == 13  # one failed, one without energy


def test_single_row_or_categorical_pair_has_no_map():
    speed = np.array([0.1, 0.2, 0.1, 0.2])
    gait = np.array(["tripod", "tripod", "wave", "wave"])
    parameters, metrics, units, status = table({"gait": gait, "speed": speed}, failed=0)
    names = [name for name, _ in sweep_figures(parameters, metrics, units, status, "t")]
    assert not any(name.endswith("-map.png") for name in names)
    assert sweep_figures({}, metrics, units, status, "t") == []


def test_file_names_are_safe_and_distinct():
    height = np.array([0.01, 0.02, 0.03])
    metrics = {"peak force:L1/tita": np.array([1.0, 2.0, 3.0]),
               "peak/force": np.array([1.0, np.nan, 2.0])}
    names = [name for name, _ in sweep_figures({"step height": height}, metrics, {},
                                               ["ok", "ok", "ok"], "t")]
    assert names == ["peak-force-vs-step-height.png", "peak-force-vs-step-height-2.png"]
    assert all(SAFE.fullmatch(name) for name in names)


def test_every_figure_renders(grid, random_pair):
    for *_, figures in (grid, random_pair):
        for name, figure in figures.items():
            assert SAFE.fullmatch(name)
            assert png_bytes(figure, dpi=50).startswith(b"\x89PNG\r\n\x1a\n"), name


def test_no_pyplot_and_no_matplotlib_use():
    tree = ast.parse((Path(__file__).resolve().parent.parent / "hexapod" / "output"
                      / "sweep_figures.py").read_text())
    nodes = [node for node in ast.walk(tree) if isinstance(node, ast.Import | ast.ImportFrom)]
    imported = [alias.name for node in nodes for alias in node.names]
    imported += [node.module for node in nodes if isinstance(node, ast.ImportFrom)]
    assert not any("pyplot" in (name or "") for name in imported)
    assert not any(isinstance(node, ast.Attribute) and node.attr == "use"
                   for node in ast.walk(tree))


def test_an_infeasible_case_is_drawn_in_a_map_only_marked():
    """A case the ground cannot hold (status infeasible) keeps its value in the heat map, in a
    cell hatched orange and labelled INFEASIBLE, is left out of the lines and marked there with
    an orange cross, and is counted in the titles."""
    duty = np.repeat([0.6, 0.75], 3)
    speed = np.tile([0.4, 0.8, 1.2], 2)
    parameters, metrics, units, status = table({"duty": duty, "speed": speed}, failed=0)
    status[0] = "ok"  # no failed case here: metrics of case 0 stay NaN, as a failed one's
    status[5] = "infeasible"  # duty 0.75, speed 1.2
    figures = dict(sweep_figures(parameters, metrics, units, status, "speed study"))
    heat = figures["peak_effort-map.png"]
    ax = heat.axes[0]
    data = np.ma.filled(ax.images[0].get_array().astype(float), np.nan)
    stacked = np.column_stack([metrics[f"peak_effort:{j}"] for j in JOINTS])
    assert data[2, 1] == np.nanmax(stacked[5])  # row: speed 1.2, column: duty 0.75
    (cell,) = [t for t in ax.texts if t.get_position() == (1, 2)]
    assert cell.get_text().startswith("INFEASIBLE\n")
    hatched = [p for p in ax.patches if p.get_hatch() == "xx"]
    assert [p.get_xy() for p in hatched] == [(0.5, 1.5)]
    assert "(infeasible 1)" in heat.get_suptitle()
    lines = figures["peak_effort-vs-speed.png"].axes[0]
    np.testing.assert_array_equal(line(lines, "infeasible").get_xdata(), [1.2])
    envelope = np.nanmax(stacked[[2]], axis=1)  # speed 1.2: only duty 0.6's case is drawn
    drawn = [a for a in lines.lines if a.get_gid() in JOINTS]
    top = max(np.nanmax(a.get_ydata()[2:]) for a in drawn)
    assert top == envelope[0]
