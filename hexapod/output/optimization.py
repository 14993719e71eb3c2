"""What ``hexapod optimize`` writes about its run: the log of the optimiser's evaluations
(``optimization.csv``), the optimum (``optimum.csv``), a summary and a convergence figure
(``optimization.png``). The optimum's own report and scene file are written beside them by the
command. Each function reads an :class:`hexapod.sweeps.optimize.OptimizationRun` (``run``)."""

from __future__ import annotations

import csv
import io
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: The columns of ``optimum.csv``: name -> (unit, meaning).
OPTIMUM_COLUMNS = {
    "parameter": (None, "the scene key of the parameter"),
    "low": (None, "its lower bound, in 'unit'"),
    "high": (None, "its upper bound, in 'unit'"),
    "start": (None, "its value at the start, in 'unit'"),
    "optimum": (None, "its value at the optimum, in 'unit'"),
    "unit": (None, "the parameter's unit"),
}


def log_columns(run, objective_unit: str) -> dict:
    """The columns of ``optimization.csv``: name -> (unit, meaning)."""
    columns = {"evaluation": ("1", "the optimiser's evaluation of the problem, in order"),
               "objective": (objective_unit or "1", f"the figure of merit minimised, "
                             f"{run.spec.minimize}"),
               "violation": ("1", "the largest constraint excess, relative to its bound (0: "
                             "every constraint met)")}
    for change in run.parameters:
        columns[f"value:{change.name}"] = (change.unit, "the parameter's value")
    return columns


def log_csv_text(run) -> str:
    """``optimization.csv``: one row per evaluation, numbers to round-trip."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["evaluation", "objective", "violation"]
                    + [f"value:{c.name}" for c in run.parameters])
    for entry in run.log:
        writer.writerow([entry.index, repr(float(entry.objective)), repr(float(entry.violation)),
                         *(repr(float(v)) for v in entry.values)])
    return out.getvalue()


def optimum_csv_text(run) -> str:
    """``optimum.csv``: one row per parameter."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(list(OPTIMUM_COLUMNS))
    for change, bound, start, best in zip(run.parameters, run.spec.bounds, run.start,
                                          run.optimum, strict=True):
        si = change.scene_scale
        writer.writerow([change.name, repr(bound.low * si), repr(bound.high * si),
                         repr(float(start)), repr(float(best)), change.unit])
    return out.getvalue()


def optimization_summary(run, objective_unit: str) -> str:
    """``summary.md``: the problem, how IPOPT ended, the optimum and its check."""
    spec, name = run.spec, run.spec.minimize
    start_value = run.start_objective
    unit = f" {objective_unit}" if objective_unit else ""
    lines = [f"# Optimisation: {spec.study.name}", "",
             f"Minimise `{name}` over {len(run.parameters)} parameter(s) by IPOPT "
             f"(limited-memory Hessian, exact gradients): **{run.status}** after "
             f"{run.iterations} iterations and {len(run.log)} evaluations.", "",
             f"- `{name}`: {start_value:.10g}{unit} at the start, "
             f"{run.checked[name]:.10g}{unit} at the optimum "
             f"({_change(start_value, run.checked[name])}).",
             f"- The optimum checked by a run of the scene re-read with its values "
             f"(`optimum.toml`): the figures predicted from the start's run agree to "
             f"{run.agreement:.1e} (relative).", "",
             "| parameter | low | high | start | optimum | unit |", "| --- | --- | --- | --- | "
             "--- | --- |"]
    for change, bound, start, best in zip(run.parameters, spec.bounds, run.start, run.optimum,
                                          strict=True):
        low, high = bound.low * change.scene_scale, bound.high * change.scene_scale
        at_bound = " (at a bound)" if best in (low, high) else ""
        lines.append(f"| `{change.name}` | {low:g} | {high:g} | {start:.6g} | "
                     f"{best:.10g}{at_bound} | {change.unit} |")
    if run.limits:
        lines += ["", "| constraint | min | max | at the optimum |", "| --- | --- | --- | --- |"]
        for limit in run.limits:
            matched = [c for c in run.checked if _matches(c, limit.pattern)]
            worst = max(matched, key=lambda c: run.checked[c], default=None)
            shown = f"{run.checked[worst]:.6g} (`{worst}`)" if worst else "none"
            lines.append(f"| `{limit.pattern}` | {limit.low:g} | {limit.high:g} | {shown} |")
    return "\n".join(lines) + "\n"


def _matches(column: str, pattern: str) -> bool:
    from fnmatch import fnmatchcase

    return fnmatchcase(column, pattern)


def _change(before: float, after: float) -> str:
    if not before:
        return "from zero"
    return f"{100 * (after - before) / abs(before):+.2f} %"


def convergence_figure(run, objective_unit: str) -> Figure:
    """The figure of merit and the largest constraint excess at each evaluation, and each
    parameter's path between its bounds (as a fraction of the range).

    Parameters
    ----------
    run : hexapod.sweeps.optimize.OptimizationRun
    objective_unit : str

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure

    figure = Figure(figsize=(7.5, 5.0))
    top, bottom = figure.subplots(2, 1, sharex=True)
    k = np.array([e.index for e in run.log])
    top.plot(k, [e.objective for e in run.log], marker=".", color="#4c72b0")
    top.set_ylabel(f"{run.spec.minimize}" + (f" ({objective_unit})" if objective_unit else ""),
                   fontsize=8)
    if any(e.violation > 0 for e in run.log):
        excess = top.twinx()
        excess.plot(k, [e.violation for e in run.log], color="#c44e52", linewidth=0.8)
        excess.set_ylabel("constraint excess (relative)", color="#c44e52", fontsize=8)
    values = np.array([e.values for e in run.log]).reshape(len(run.log), -1)
    for p, (change, bound) in enumerate(zip(run.parameters, run.spec.bounds, strict=True)):
        low, high = bound.low * change.scene_scale, bound.high * change.scene_scale
        bottom.plot(k, (values[:, p] - low) / (high - low), label=change.name)
    bottom.set_ylim(-0.05, 1.05)
    bottom.set_ylabel("parameter within its range", fontsize=8)
    bottom.set_xlabel("evaluation")
    if len(run.parameters) <= 8:
        bottom.legend(fontsize=7, loc="best")
    figure.suptitle(f"{run.spec.study.name}: {run.status}", fontsize=10)
    return figure
