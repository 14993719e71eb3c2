"""The extreme-case check behind ``hexapod check``: where each method breaks, why, and what to use.

Every method on every case (:func:`run_suite`): finished or failed and why, steps, rejected steps,
CPU time, largest constraint drift, energy error, error against an independent reference where
the case has one, the condition number along the run; and, per case, the method to use
(:func:`recommend`). With it, the stability of the explicit methods on stiff springs
(:mod:`hexapod.benchmarks.stable_steps`), and the report that gathers both (:func:`report_files`).

A run that finishes with a state grown out of bounds is reported as ``diverged``, not finished.
"""

from __future__ import annotations

import csv
import io
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from hexapod.algorithms.dynamics import forward_dynamics
from hexapod.algorithms.kinematics import consistent_state
from hexapod.benchmarks.stable_steps import (
    STABILITY_COLUMNS,
    StabilityRow,
    stability_figure,
    stability_table,
)
from hexapod.model.model import Model
from hexapod.simulation.loop import simulate
from hexapod.simulation.registry import DEFAULT_METHOD, INTEGRATORS
from hexapod.simulation.results import Columns, SimulationResult, units_json

#: where no run of a case is accurate, its adaptive methods run again at tolerances this much
#: smaller (a long horizon or a motion near an unstable equilibrium needs them)
RETRY_TIGHTER = 1e-3
#: a run is accurate when its error against the reference (relative) is below this; without a
#: reference, when the energy error (relative to the largest kinetic energy) is below it and
#: the constraints held to DRIFT_LIMIT
ACCURACY = 1e-3
DRIFT_LIMIT = 1e-6
#: saved states at which the condition number is evaluated along a run
CONDITION_SAMPLES = 25
#: CPU seconds after which a run is stopped (reported as stopped by the budget): the whole
#: suite, and ``--quick``, whose runs are short enough to need no more where they work
BUDGET = 60.0
QUICK_BUDGET = 5.0


# ------------------------------------------------------------------ every method on every case

@dataclass
class SuiteCase:
    """One case of the suite. ``error(result)``: relative error of a run against an
    independent reference, or None when the case has none."""

    name: str
    category: str
    description: str
    model: Model
    t_end: float
    error: Callable[[SimulationResult], float] | None = None
    step: float | None = None  # of fixed-step methods (default: t_end / 1000)
    rtol: float = 1e-6
    atol: float = 1e-8
    notes: list[str] = field(default_factory=list)


@dataclass
class CaseRun:
    """One method on one case."""

    case: str
    category: str
    method: str
    setting: str
    status: str  # "finished", "failed", "diverged", "stopped" (by the CPU budget)
    reason: str
    steps: int
    rejected: int
    crossings: int  # singular configurations crossed with nearly dependent rows left out
    cpu_time: float  # of the time loop, s
    wall_time: float  # of the time loop, s
    position_drift: float
    velocity_drift: float
    energy_error: float | None
    error: float | None
    condition_max: float
    sigma_min: float
    redundant_rows: list[str]
    accurate: bool
    #: the factor on the case's tolerances (below 1: a retry, see run_suite)
    tighter: float = 1.0
    #: the run itself, kept for the default method only (the condition figure draws it)
    result: SimulationResult | None = field(default=None, repr=False, compare=False)

    def as_dict(self) -> dict:
        return {name: getattr(self, name) for name in self.__dataclass_fields__
                if name != "result"}


def _from_mechanism(case, step_count: int | None = None, rtol: float = 1e-6) -> SuiteCase:
    """A case of :mod:`hexapod.benchmarks`, assembled, judged against its reference."""
    from hexapod.algorithms.assembly import assemble

    model = assemble(case.scene)

    def error(result: SimulationResult) -> float:
        return case.error(model, result.t, result.q)

    step = case.t_end / step_count if step_count else None
    return SuiteCase(case.name, case.category, case.description, model, case.t_end, error,
                     step=step, rtol=rtol, atol=rtol * 1e-2 * case.length, notes=case.notes)


def _standing_case(scene, t_end: float, step: float | None = None) -> SuiteCase:
    """The hexapod standing on its feet: its exact motion is rest (the pose is an equilibrium:
    gravity is vertical and the feet carry it); the error is the largest displacement of any
    body's centre of mass relative to the legs' size."""
    from hexapod.algorithms.assembly import assemble
    from hexapod.algorithms.kinematics import body_poses

    model = assemble(scene)
    data = model.create_data()
    q0, _ = consistent_state(model, data)
    start = body_poses(model, q0)[0][0]

    def error(result: SimulationResult) -> float:
        moved = np.abs(body_poses(model, result.q)[0] - start).max()
        return float(moved / model.characteristic_length)

    return SuiteCase(scene.name, "redundant", "six feet on the ground, every joint held: "
                     "the foot forces are statically indeterminate", model, t_end, error,
                     step=step)


def build_suite(quick: bool = False, standing=None) -> list[SuiteCase]:
    """The extreme cases (:mod:`hexapod.benchmarks`), and the standing hexapod when its
    scene is given. ``quick``: the same kinds of case with shorter horizons and fewer fixed
    steps (at the same step size where that matters), one stiffness in two (a smoke test of
    about a minute, and the cases of the tests)."""
    import hexapod.benchmarks as m

    if quick:
        chosen = [(m.stiff_slider(1e3), None), (m.stiff_slider(1e9, t_end=0.02), None),
                  (m.flyball_governor(t_end=1.0), None), (m.n_four_bar(t_end=2.0), None),
                  (m.bricard(t_end=1.0), 500), (m.four_bar_dead_points(), None),
                  (m.mass_ratio(t_end=0.2), None), (m.stretched_leg(), None),
                  (m.long_pendulum(periods=10), 1000), (m.large_step_pendulum(periods=2), 20)]
    else:
        chosen = [(m.stiff_slider(k), None) for k in (1e3, 1e5, 1e7, 1e9)] + [
            (m.stiff_spring_pendulum(), None), (m.flyball_governor(), None),
            (m.n_four_bar(), None), (m.n_four_bar(40, t_end=20.0), None),
            (m.n_four_bar(dimension=3), None), (m.bricard(), None),
            (m.four_bar_dead_points(), None), (m.four_bar_dead_points(driven=True), None),
            (m.mass_ratio(), None), (m.mass_ratio_pendulum(), None), (m.stretched_leg(), None),
            (m.stretched_leg(driven=True), None),
            # the long horizon, the IFToMM pendulum's 2000 s: 1e5 fixed steps (about 85 per
            # period); very large steps: 10 per period
            (m.long_pendulum(duration=2000.0), 100_000), (m.large_step_pendulum(), 100)]
    cases = [_from_mechanism(case, steps) for case, steps in chosen]
    if standing is not None:  # quick: 100 steps of the full suite's 2e-3 s
        cases.append(_standing_case(standing, 0.2, 2e-3) if quick
                     else _standing_case(standing, 2.0))
    return cases


def scene_case(name: str, model: Model, t_end: float) -> SuiteCase:
    """A user's scene as a case: no reference, judged by its drift and energy."""
    return SuiteCase(name, "scene", "the given scene", model, t_end)


def _setting(case: SuiteCase, method: str) -> dict:
    if INTEGRATORS[method].adaptive:
        return {"rtol": case.rtol, "atol": case.atol}
    return {"step": case.step or case.t_end / 1000}


def _label(setting: dict) -> str:
    return f"h={setting['step']:.3g}" if "step" in setting else f"rtol={setting['rtol']:.0e}"


def _along_run(model: Model, result: SimulationResult) -> tuple[float, float, list[str]]:
    """Largest condition number and smallest singular value of the equilibrated system over
    saved states, and the rows found redundant on the way."""
    count = result.t.size
    picks = np.unique(np.linspace(0, count - 1, min(CONDITION_SAMPLES, count)).astype(int))
    worst, smallest, redundant = 1.0, np.inf, {}
    data = model.create_data()
    for k in picks:
        q, v = result.q[k], result.v[k]
        if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
            break
        try:
            forward_dynamics(model, data, float(result.t[k]), q, v, condition=True)
        except Exception:  # noqa: BLE001 - a state the run reached but the solve refuses
            worst = np.inf
            break
        worst = max(worst, data.condition_number)
        smallest = min(smallest, data.sigma_min)
        for row in data.redundant_rows:
            redundant[model.rows[row].name] = None
    return float(worst), float(smallest), list(redundant)


def _at_rest(model: Model, result: SimulationResult) -> bool:
    """Whether the run never moved (its largest kinetic energy is round-off)."""
    picks = np.linspace(0, result.t.size - 1, min(CONDITION_SAMPLES, result.t.size)).astype(int)
    kinetic = max(float(model.energy(result.q[k], result.v[k])[0]) for k in picks)
    return kinetic < 1e-20


def _diverged(result: SimulationResult) -> str:
    """Why a finished run is not to be believed: non-finite or runaway states."""
    if not (np.all(np.isfinite(result.q)) and np.all(np.isfinite(result.v))):
        return "the state became non-finite"
    speed = np.abs(result.v).max(axis=1)
    if speed[-1] > 1e3 * max(speed[0], np.median(speed), 1e-3):
        return f"speeds grew from {speed[0]:.3g} to {speed[-1]:.3g} (unstable step)"
    return ""


def run_case(case: SuiteCase, method: str, *, budget: float = BUDGET,
             tighter: float = 1.0) -> CaseRun:
    """One method on one case, at the case's setting for it (an adaptive method's tolerances
    multiplied by ``tighter``); stopped after ``budget`` CPU seconds of its time loop."""
    setting = _setting(case, method)
    if "rtol" in setting:
        setting = {name: value * tighter for name, value in setting.items()}
    result = simulate(case.model, case.t_end, method=method, forces=False, cpu_budget=budget,
                      **setting)
    status, reason = result.status, result.message
    if status == "failed" and "CPU budget" in reason:  # the loop's words when it stops a run
        status = "stopped"
    if result.success:
        why = _diverged(result)
        if why:
            status, reason = "diverged", why
    conserved = result.energy_drift if case.model.energy_conserved else None
    if conserved is not None and _at_rest(case.model, result):
        conserved = None  # relative to a kinetic energy of zero: meaningless
    error = None
    if status == "finished" and case.error is not None:
        error = float(case.error(result))
    condition, sigma, redundant = _along_run(case.model, result)
    if status != "finished":
        accurate = False
    elif error is not None:
        accurate = error <= ACCURACY
    else:
        accurate = (result.max_position_violation <= DRIFT_LIMIT
                    and (conserved is None or conserved <= ACCURACY))
    return CaseRun(case.name, case.category, method, _label(setting), status, reason,
                   result.counters.steps, result.counters.rejected,
                   result.counters.crossings, result.cpu_time, result.wall_time,
                   result.max_position_violation, result.max_velocity_violation, conserved,
                   error, condition, sigma, redundant, accurate,
                   tighter=tighter,
                   result=result if method == DEFAULT_METHOD else None)


def run_suite(cases: list[SuiteCase], methods=None, *, budget: float = BUDGET,
              progress: Callable[[str], None] | None = None) -> list[CaseRun]:
    """Every method (default: the registry) on every case. Where no run is accurate, the
    adaptive methods that finished run again with tolerances ``RETRY_TIGHTER`` times smaller,
    so that the recommendation names a setting that works when one does. ``progress`` hears of
    each run as it starts and ends (its time loop's wall and CPU time, and the whole run's wall
    time with the error and condition numbers evaluated after it)."""
    runs = []

    def run(case, method, tighter=1.0):
        if progress:
            progress(f"{case.name}: {method}")
        started = time.perf_counter()
        runs.append(run_case(case, method, budget=budget, tighter=tighter))
        if progress:
            done = runs[-1]
            outcome = ("stopped by the CPU budget" if done.status == "stopped" else done.status)
            progress(f"{case.name}: {method} ({done.setting}) {outcome}"
                     f"{' (accurate)' if done.accurate else ''}: time loop "
                     f"{done.wall_time:.1f} s wall, {done.cpu_time:.1f} s CPU "
                     f"({time.perf_counter() - started:.1f} s wall in all)")

    for case in cases:
        first = len(runs)
        for method in methods or INTEGRATORS:
            run(case, method)
        mine = runs[first:]
        if not any(r.accurate for r in mine):
            for r in mine:
                if r.status == "finished" and INTEGRATORS[r.method].adaptive:
                    run(case, r.method, RETRY_TIGHTER)
    return runs


def recommend(runs: list[CaseRun]) -> str:
    """The method to use on one case: the cheapest accurate run; else the most accurate."""
    good = sorted((r for r in runs if r.accurate), key=lambda r: r.cpu_time)
    if good:
        best = good[0]
        others = ", ".join(list(dict.fromkeys(
            r.method for r in good[1:] if r.method != best.method))[:3])
        return (f"{best.method} at {best.setting} ({best.cpu_time:.3g} s)"
                + (f"; also accurate: {others}" if others else ""))
    finished = [r for r in runs if r.status == "finished"]
    if finished:
        best = min(finished, key=lambda r: (r.error if r.error is not None else np.inf,
                                            r.position_drift))
        return f"none accurate to {ACCURACY:g}; closest: {best.method} (tighten its setting)"
    return "none finished"


def _number(x, digits: int = 2) -> str:
    if x is None:
        return "-"
    if not np.isfinite(x):
        return "inf"
    return f"{x:.{digits}g}" if abs(x) >= 1e-3 or x == 0 else f"{x:.{digits - 1}e}"


def suite_table(runs: list[CaseRun]) -> str:
    """Markdown: one row per run, the recommendation after each case."""
    lines = ["| case | method | setting | outcome | steps | rejected | crossings | CPU (s) | "
             "wall (s) | drift | energy error | error | max cond | min sigma |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for case in dict.fromkeys(r.case for r in runs):
        mine = [r for r in runs if r.case == case]
        for r in mine:
            outcome = r.status + (", accurate" if r.accurate else "")
            if r.status == "stopped":  # the reason says by what: "stopped by the CPU budget"
                outcome = r.reason.split(": ", 1)[-1][:90]
            elif r.status != "finished":
                outcome += ": " + r.reason.split(": ", 1)[-1][:90]
            lines.append(
                f"| {case} | {r.method} | {r.setting} | {outcome} | {r.steps} | {r.rejected} | "
                f"{r.crossings} | {r.cpu_time:.3g} | {r.wall_time:.3g} | "
                f"{_number(r.position_drift)} | "
                f"{_number(r.energy_error)} | "
                f"{_number(r.error)} | {_number(r.condition_max)} | {_number(r.sigma_min)} |")
        lines.append(f"| **{case}** | **use** | | {recommend(mine)} | | | | | | | | | | |")
    return "\n".join(lines)


def time_total(runs: list[CaseRun]) -> str:
    """The time of every run's time loop added up, CPU and wall, and the runs the budget
    stopped."""
    stopped = sum(r.status == "stopped" for r in runs)
    return (f"{len(runs)} runs: {sum(r.cpu_time for r in runs):.1f} s CPU, "
            f"{sum(r.wall_time for r in runs):.1f} s wall in their time loops"
            + (f"; {stopped} stopped by the CPU budget" if stopped else ""))


def recommendations(runs: list[CaseRun], cases: list[SuiteCase]) -> str:
    """Markdown: per case, its category, what is extreme about it, the recommendation."""
    lines = ["| case | category | what is extreme | redundant rows | use |",
             "|---|---|---|---|---|"]
    for case in cases:
        mine = [r for r in runs if r.case == case.name]
        redundant = sorted({row for r in mine for row in r.redundant_rows})
        shown = ", ".join(redundant[:4]) + (f" (+{len(redundant) - 4})" if len(redundant) > 4
                                           else "")
        lines.append(f"| {case.name} | {case.category} | {case.description} | "
                     f"{shown or '-'} | {recommend(mine)} |")
    return "\n".join(lines)


#: ``runs.csv``: one row per run, a column per field of :class:`CaseRun` (unit, meaning).
RUN_COLUMNS: Columns = {
    "case": (None, "the case"), "category": (None, "what kind of case"),
    "method": (None, "the integrator"), "setting": (None, "its tolerances or step"),
    "status": (None, "finished, failed, diverged or stopped (by the CPU budget)"),
    "reason": (None, "why it stopped"),
    "steps": ("1", "accepted steps"), "rejected": ("1", "rejected steps"),
    "crossings": ("1", "singular poses crossed"), "cpu_time": ("s", "CPU time of the time loop"),
    "wall_time": ("s", "wall-clock time of the time loop"),
    "position_drift": ("1", "largest scaled constraint residual |phi_i| / s_i"),
    "velocity_drift": ("1/s", "largest scaled velocity residual |Phi_v v - nu|_i / s_i"),
    "energy_error": ("1", "largest energy error relative to the largest kinetic energy"),
    "error": ("1", "relative error against the case's reference"),
    "condition_max": ("1", "largest condition number along the run (equilibrated)"),
    "sigma_min": ("1", "smallest singular value of the equilibrated Phi_v along the run"),
    "redundant_rows": (None, "redundant constraint rows met, space-separated"),
    "accurate": (None, "True or False: within the accuracy of the check"),
    "tighter": ("1", "factor on the case's tolerances (below 1: a retry)"),
}


def runs_csv(runs: list[CaseRun]) -> str:
    rows = [{**r.as_dict(), "redundant_rows": " ".join(r.redundant_rows)} for r in runs]
    return _rows_csv(rows) if rows else ""


def units_json_text(runs: list[CaseRun], stability: list[StabilityRow]) -> str:
    """``units.json`` of ``hexapod check``: every column of ``runs.csv`` (and of
    ``stability.csv``) with its unit and meaning."""
    fields = [n for n in CaseRun.__dataclass_fields__ if n != "result"]
    tables = {"runs.csv": {n: RUN_COLUMNS[n] for n in fields} if runs else {}}
    if stability:
        tables["stability.csv"] = STABILITY_COLUMNS
    return units_json(tables)


def outcome_figure(runs: list[CaseRun]):
    """Cases against methods: green accurate, yellow finished but inaccurate, red failed or
    diverged, grey stopped by the CPU budget; each cell gives the CPU time."""
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure

    def column(r):
        return r.method if r.tighter == 1.0 else f"{r.method}, tol x {r.tighter:g}"

    cases = list(dict.fromkeys(r.case for r in runs))
    methods = list(dict.fromkeys(column(r) for r in runs))
    grid = np.full((len(cases), len(methods)), np.nan)
    figure = Figure(figsize=(1.3 * len(methods) + 2.5, 0.42 * len(cases) + 1.6),
                    layout="constrained")
    axis = figure.subplots()
    for r in runs:
        i, j = cases.index(r.case), methods.index(column(r))
        grid[i, j] = (2 if r.accurate else 1 if r.status == "finished"
                      else 3 if r.status == "stopped" else 0)
        axis.text(j, i, f"{r.cpu_time:.2g} s" if r.status == "finished" else r.status,
                  ha="center", va="center", fontsize=7)
    axis.imshow(grid, cmap=ListedColormap(["#f4a6a6", "#f6e3a1", "#b7e4b0", "#d9d9d9"]),
                vmin=0, vmax=3, aspect="auto")
    axis.set_xticks(range(len(methods)), methods, rotation=30, ha="right", fontsize=8)
    axis.set_yticks(range(len(cases)), cases, fontsize=8)
    axis.set_title("green: accurate; yellow: finished, not accurate; red: failed or diverged; "
                   "grey: stopped by the CPU budget (CPU time in the cell)", fontsize=9)
    return figure


def condition_figure(cases: list[SuiteCase], runs: list[CaseRun], samples: int = 200):
    """The condition number of the equilibrated saddle-point matrix and the smallest singular
    value of the equilibrated ``Phi_v`` along the default method's run of each case (from
    ``runs``, or run here when the suite left the default method out)."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(7.0, 5.6), layout="constrained")
    top, bottom = figure.subplots(2, 1, sharex=True)
    kept = {r.case: r.result for r in runs if r.result is not None}
    for case in cases:
        data = case.model.create_data()
        result = kept.get(case.name) or simulate(
            case.model, case.t_end, method=DEFAULT_METHOD, rtol=case.rtol, atol=case.atol,
            forces=False, cpu_budget=60.0)
        picks = np.unique(np.linspace(0, result.t.size - 1, min(samples, result.t.size))
                          .astype(int))
        cond, sigma = [], []
        for k in picks:
            forward_dynamics(case.model, data, float(result.t[k]), result.q[k], result.v[k],
                             condition=True)
            cond.append(data.condition_number)
            sigma.append(data.sigma_min)
        fraction = result.t[picks] / case.t_end
        top.semilogy(fraction, cond, label=case.name)
        bottom.semilogy(fraction, sigma, label=case.name)
    top.set_ylabel("condition number (equilibrated)")
    bottom.set_ylabel("smallest singular value")
    bottom.set_xlabel(f"fraction of the run ({DEFAULT_METHOD})")
    top.set_title("Conditioning along the runs", fontsize=10)
    for axis in (top, bottom):
        axis.grid(True, which="both", alpha=0.3)
    top.legend(fontsize=7)
    return figure


# ------------------------------------------------------------------ the report

def diagnosis_table(diagnoses: dict) -> str:
    """Markdown: the diagnostics of each case at its start."""
    def n(x):
        return _number(x, 3)

    lines = ["| case | DOF (counted) | redundant rows | cond (equilibrated / as written) | "
             "min sigma | distance to singular | stiffness ratio | fastest mode (1/s) | "
             "stable step rk4 / dopri5 / dop853 / rattle (s) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name, d in diagnoses.items():
        steps = " / ".join(n(d.stable_steps.get(m)) for m in
                           ("rk4-baumgarte", "dopri5-projection", "dop853-projection",
                            "rattle"))
        lines.append(f"| {name} | {d.dof} ({d.dof_counted}) | {len(d.redundant_rows)} | "
                     f"{n(d.condition_number)} / {n(d.condition_number_unscaled)} | "
                     f"{n(d.sigma_min)} | {n(d.singular_distance)} | {n(d.stiffness_ratio)} | "
                     f"{n(d.fastest_rate)} | {steps} |")
    return "\n".join(lines)


def report_files(cases: list[SuiteCase], runs: list[CaseRun], diagnoses: dict,
                 stability: list[StabilityRow], command: str) -> dict[str, bytes]:
    """The files of ``hexapod check``: ``check.md``, ``runs.csv``, ``diagnostics.json``,
    ``stability.csv``, ``units.json`` and the figures (written together, atomically, by the
    caller)."""
    import json

    from hexapod.output.figures import png_bytes

    text = ["# Extreme-case check", "", f"Command: `{command}`. CPU and wall time of each "
            "run's time loop. An accurate run is within "
            f"{ACCURACY:g} of the case's independent reference (relative), or, without one, "
            f"holds the constraints to {DRIFT_LIMIT:g} and the energy to {ACCURACY:g}.", "",
            "## What to use", "", recommendations(runs, cases), "",
            "## Diagnostics at the start", "", diagnosis_table(diagnoses), ""]
    if stability:
        text += ["## Largest stable step of the explicit methods on stiff springs", "",
                 stability_table(stability), ""]
    text += ["## Every method on every case", "", time_total(runs) + ".", "",
             suite_table(runs), ""]
    files = {"check.md": "\n".join(text).encode(), "runs.csv": runs_csv(runs).encode(),
             "diagnostics.json": json.dumps(
                 {name: _finite(d.as_dict()) for name, d in diagnoses.items()},
                 indent=1).encode(),
             "units.json": units_json_text(runs, stability).encode(),
             "outcomes.png": png_bytes(outcome_figure(runs))}
    if stability:
        files["stability.csv"] = _rows_csv([r.as_dict() for r in stability]).encode()
        files["stability.png"] = png_bytes(stability_figure(stability))
    watched = [c for c in cases if c.category in ("singular", "redundant")] or cases[:1]
    files["condition.png"] = png_bytes(condition_figure(watched, runs))
    return files


def _finite(value):
    """JSON without NaN or infinity (written as null)."""
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    if isinstance(value, float | np.floating) and not np.isfinite(value):
        return None
    if isinstance(value, np.floating | np.integer):
        return value.item()
    return value


def _rows_csv(rows: list[dict]) -> str:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    return buffer.getvalue()
