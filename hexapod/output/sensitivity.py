"""What ``hexapod sensitivity`` writes: the table of derivatives (``sensitivities.csv``), its
units, a tornado figure per figure of merit and a short summary.

The table is a record table (``docs/outputs.md``): one row per figure of merit and parameter,
with the columns ``metric`` (``family:element`` as the sweeps name it), ``parameter`` (the scene
key), ``value`` (the derivative, in the row's ``unit``: the metric's unit per the
parameter's) and ``elasticity`` (``(p / m) dm/dp``: the relative change of the metric per
relative change of the parameter, NaN where the metric is zero).
"""

from __future__ import annotations

import csv
import io
import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: The columns of ``sensitivities.csv``: name -> (unit, meaning).
SENSITIVITY_COLUMNS = {
    "metric": (None, "the figure of merit, family:element as a sweep names it"),
    "parameter": (None, "the scene key of the parameter"),
    "value": (None, "the derivative of the metric with respect to the parameter, in 'unit'"),
    "unit": (None, "the derivative's unit: the metric's per the parameter's"),
    "elasticity": ("1", "(p / m) dm/dp, the relative change of the metric per relative change "
                   "of the parameter"),
}
#: The parameters a tornado figure shows, the largest elasticities first.
TORNADO_BARS = 15


def sensitivity_csv_text(rows: list[dict]) -> str:
    """``sensitivities.csv``: the rows of
    :func:`hexapod.sweeps.metric_derivatives.sensitivity_rows`, numbers to round-trip."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(list(SENSITIVITY_COLUMNS))
    for row in rows:
        writer.writerow([row["metric"], row["parameter"], repr(float(row["value"])), row["unit"],
                         repr(float(row["elasticity"]))])
    return out.getvalue()


def tornado_metrics(metrics: dict[str, float], columns) -> dict[str, str]:
    """The figures of merit drawn, one per family: the family's element of largest value
    (the critical joint or foot), or the family's one value. Returns family -> metric."""
    chosen: dict[str, str] = {}
    for column in columns:
        family = column.partition(":")[0]
        value = metrics[column]
        best = chosen.get(family)
        if best is None or (np.isfinite(value) and not abs(value) <= abs(metrics[best])):
            chosen[family] = column
    return chosen


def tornado_figure(rows: list[dict], metric: str, value: float, unit: str) -> Figure:
    """The elasticities of one figure of merit with respect to each parameter, largest first
    (at most :data:`TORNADO_BARS`), as horizontal bars: how many per cent the metric moves
    for one per cent of each parameter.

    Parameters
    ----------
    rows : list of dict
        The table's rows (all metrics: those of ``metric`` are drawn).
    metric : str
        The figure of merit.
    value : float
        Its value, for the title.
    unit : str
        Its unit, for the title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    mine = [r for r in rows if r["metric"] == metric and np.isfinite(r["elasticity"])]
    mine.sort(key=lambda r: -abs(r["elasticity"]))
    shown = mine[:TORNADO_BARS][::-1]
    height = 1.2 + 0.28 * max(len(shown), 1)
    figure = Figure(figsize=(7.0, height))
    ax = figure.add_axes((0.42, 0.7 / height, 0.53, 1 - 1.25 / height))
    elasticity = np.array([r["elasticity"] for r in shown])
    ax.barh(np.arange(len(shown)), elasticity,
            color=["#c44e52" if e > 0 else "#4c72b0" for e in elasticity])
    ax.set_yticks(np.arange(len(shown)), [r["parameter"] for r in shown], fontsize=8)
    ax.set_ylim(-0.6, len(shown) - 0.4)
    ax.grid(axis="x", color="0.9", linewidth=0.6)
    ax.axvline(0.0, color="0.3", linewidth=0.8)
    ax.set_xlabel("elasticity (p / m) dm/dp")
    left_out = len(mine) - len(shown)
    more = f"; {left_out} smaller left out" if left_out > 0 else ""
    shown_value = f"{value:.4g} {unit}".strip() if math.isfinite(value) else "nan"
    figure.suptitle(f"{metric} = {shown_value}\n(red: grows with the parameter{more})",
                    fontsize=10)
    return figure


def sensitivity_summary(scene_name: str, metrics: dict[str, float], rows: list[dict],
                        chosen: dict[str, str], samples: int, run_time: float,
                        changes: np.ndarray | None = None, infeasible: int = 0) -> str:
    """``summary.md``: per figure of merit drawn, its value and its three largest
    elasticities; with the friction policy, the samples where its active set changes
    (``changes``, s); the samples where the ground cannot give the feet their forces
    (``infeasible``), said first."""
    lines = [f"# Design sensitivities: {scene_name}", ""]
    if infeasible:
        lines += [f"**Infeasible**: at {infeasible} of {samples} samples the ground cannot give "
                  "the feet their forces (a foot slips or is pulled, whatever the policy): "
                  "these figures and their derivatives are not ones to size motors by.", ""]
    lines += [f"{samples} samples of the inverse dynamics; the derivatives are exact (the "
              f"saddle-point solve and the policy applied to the derivatives of the forces), "
              f"{run_time:.3g} s.", ""]
    if changes is not None and changes.size:
        shown = ", ".join(f"{t:.4g}" for t in changes[:12]) + (", ..." if changes.size > 12
                                                                else "")
        lines += [f"The friction policy's active set changes at {changes.size} samples (t = "
                  f"{shown} s): derivatives of peaks there are one-sided.", ""]
    lines += ["| figure of merit | value | largest elasticities |", "| --- | --- | --- |"]
    for metric in chosen.values():
        mine = sorted((r for r in rows if r["metric"] == metric
                       and np.isfinite(r["elasticity"])), key=lambda r: -abs(r["elasticity"]))
        top = ", ".join(f"`{r['parameter']}` {r['elasticity']:+.3g}" for r in mine[:3])
        lines.append(f"| `{metric}` | {metrics[metric]:.4g} | {top or 'none'} |")
    return "\n".join(lines) + "\n"


def derivatives_npz_bytes(model, result, sensitivity) -> bytes:
    """``derivatives.npz``: the per-sample derivatives of an inverse-dynamics result, the
    parameters along the last axis of each array, each array's unit its quantity's unit per
    the parameter's: ``times`` (N), ``parameters`` and ``parameter_units`` (P), ``joints`` and
    ``effort_units`` (J), ``effort`` (N, J, P), ``force`` (N, J, 3, P, N per unit) and
    ``torque`` (N m per unit) in the axes ``frame`` names, ``contacts`` and ``ground_force``
    (N, C, 3, P, world axes), ``coordinates``, ``coordinate_units`` and ``q`` (N, n_q, P), and
    ``active_set_changes`` (the friction policy's, s)."""
    from hexapod._support.signals import deferred
    from hexapod.model.units import COORDINATE_UNITS, component

    arrays = {"times": result.times,
              "parameters": np.array([c.name for c in sensitivity.parameters], dtype=str),
              "parameter_units": np.array([c.unit for c in sensitivity.parameters], dtype=str),
              "joints": np.array([j.name for j in model.joints], dtype=str),
              "effort_units": np.array([j.type.effort_unit or "" for j in model.joints],
                                       dtype=str),
              "effort": sensitivity.effort, "force": sensitivity.force,
              "torque": sensitivity.torque, "frame": np.array(result.frame),
              "contacts": np.array([c.name for c in model.contacts], dtype=str),
              "ground_force": sensitivity.ground_force,
              "coordinates": np.array(model.coordinate_names, dtype=str),
              "coordinate_units": np.array([COORDINATE_UNITS[component(n)][0]
                                            for n in model.coordinate_names], dtype=str),
              "q": sensitivity.q, "active_set_changes": sensitivity.active_set_changes}
    buffer = io.BytesIO()
    with deferred():  # as the simulation's npz: a signal inside ZipFile is held back
        np.savez_compressed(buffer, **arrays)
    return buffer.getvalue()

