"""The extreme-case suite behind ``hexapod check``: where each method breaks, why, and what to use.

Two studies.

* **Stability of the explicit methods on stiff springs.** For a 1 kg block on a spring-damper of
  stiffness 1e3 .. 1e9 N/m, the largest stable step predicted by :func:`hexapod.diagnostics.
  diagnose` (the method's stability region along the linearised modes) against the one observed:
  for fixed-step methods the largest step whose run does not gain energy (bisection), for
  adaptive ones the median step their controller settles on once the motion has died out (the
  controller then works at the edge of the stability region: Hairer and Wanner, *Solving ODEs
  II*, IV.2).
* **Every method on every case** (:func:`run_suite`): finished or failed and why, steps,
  rejected steps, CPU time, largest constraint drift, energy error, error against an independent
  reference where the case has one, the condition number along the run; and, per case, the
  method to use (:func:`recommend`).

A run that finishes with a state grown out of bounds is reported as ``diverged``, not finished.
"""

from __future__ import annotations

import csv
import io
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field

import numpy as np

from hexapod.diagnostics import diagnose
from hexapod.dynamics import forward_dynamics
from hexapod.integrators import DEFAULT_METHOD, INTEGRATORS
from hexapod.kinematics import consistent_state
from hexapod.model import Data, Model
from hexapod.results import SimulationResult
from hexapod.simulate import simulate

#: a run is accurate when its error against the reference (relative) is below this; without a
#: reference, when the energy error (relative to the largest kinetic energy) is below it and
#: the constraints held to DRIFT_LIMIT
ACCURACY = 1e-3
DRIFT_LIMIT = 1e-6
#: saved states at which the condition number is evaluated along a run
CONDITION_SAMPLES = 25


# ------------------------------------------------------------------ stability of explicit methods

@dataclass
class StabilityRow:
    """One explicit method on one stiff spring: predicted and observed largest stable step."""

    stiffness: float
    method: str
    predicted: float
    observed: float
    how: str  # "bisection" (fixed step) or "median step" (adaptive)

    @property
    def ratio(self) -> float:
        return self.observed / self.predicted

    def as_dict(self) -> dict:
        return {**asdict(self), "ratio": self.ratio}


def _energy(model: Model, q: np.ndarray, v: np.ndarray) -> float:
    kinetic, potential = model.energy(q, v)
    return float(kinetic) + float(potential)


def _grows(model: Model, method: str, step: float, steps: int) -> bool:
    """Whether ``steps`` fixed steps of ``step`` gain energy on a damped scene (the mark of an
    unstable step: the exact motion loses energy)."""
    with np.errstate(over="ignore", invalid="ignore"):  # an unstable step overflows
        result = simulate(model, step * steps, method=method, step=step, forces=False)
    if not result.success or not np.all(np.isfinite(result.q[-1])):
        return True
    start = _energy(model, result.q[0], result.v[0])
    tail = max(_energy(model, q, v) for q, v in zip(result.q[-steps // 5:],
                                                   result.v[-steps // 5:], strict=True))
    return tail > start


def observed_stable_step(model: Model, method: str, predicted: float, *, steps: int = 300,
                         bisections: int = 14) -> tuple[float, str]:
    """The largest stable step observed (see the module's description) and how it was found.

    ``model`` must be damped and start away from rest so that a stable run loses energy."""
    cls = INTEGRATORS[method]
    if cls.adaptive:
        result = simulate(model, 1500 * predicted, method=method, rtol=1e-4, atol=1e-10,
                          forces=False)
        accepted = np.diff(result.t)
        return float(np.median(accepted[accepted.size // 2:])), "median step"
    low, high = predicted / 8, predicted * 8
    if _grows(model, method, low, steps) or not _grows(model, method, high, steps):
        return float("nan"), "bisection (no bracket)"
    for _ in range(bisections):
        mid = np.sqrt(low * high)
        if _grows(model, method, mid, steps):
            high = mid
        else:
            low = mid
    return float(np.sqrt(low * high)), "bisection"


def explicit_methods() -> list[str]:
    """The registered methods with a stability limit (explicit ones)."""
    return [name for name, cls in INTEGRATORS.items()
            if cls.largest_stable_step([1j]) is not None]


def stability_study(scene_of: Callable[[float], object], stiffnesses=(1e3, 1e5, 1e7, 1e9),
                    methods=None, progress: Callable[[str], None] | None = None,
                    assemble: Callable | None = None) -> list[StabilityRow]:
    """Predicted and observed largest stable steps of the explicit ``methods`` on the scenes
    ``scene_of(stiffness)`` (damped, released away from rest)."""
    from hexapod.assembly import assemble as default_assemble

    build = assemble or default_assemble
    rows = []
    for k in stiffnesses:
        model = build(scene_of(k))
        q, v = consistent_state(model)
        diagnosis = diagnose(model, 0.0, q, v, methods=methods or explicit_methods(),
                             distance=False)
        for method, predicted in diagnosis.stable_steps.items():
            if predicted is None or not np.isfinite(predicted):
                continue
            if progress:
                progress(f"stability: {method} at k = {k:.0e} N/m")
            observed, how = observed_stable_step(model, method, predicted)
            rows.append(StabilityRow(float(k), method, float(predicted), observed, how))
    return rows


def stability_table(rows: list[StabilityRow]) -> str:
    lines = ["| stiffness (N/m) | method | predicted step (s) | observed step (s) | "
             "observed / predicted | observed by |", "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r.stiffness:.0e} | {r.method} | {r.predicted:.3e} | "
                     f"{r.observed:.3e} | {r.ratio:.2f} | {r.how} |")
    return "\n".join(lines)


def stability_figure(rows: list[StabilityRow]):
    """Predicted (lines) and observed (markers) largest stable steps against stiffness."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, axis = plt.subplots(figsize=(7.0, 4.6), layout="constrained")
    methods = list(dict.fromkeys(r.method for r in rows))
    for k, method in enumerate(methods):
        mine = [r for r in rows if r.method == method]
        stiffness = [r.stiffness for r in mine]
        colour = f"C{k % 10}"
        axis.loglog(stiffness, [r.predicted for r in mine], "-", color=colour,
                    label=f"{method}: predicted")
        axis.fill_between(stiffness, [r.predicted / 2 for r in mine],
                          [r.predicted * 2 for r in mine], color=colour, alpha=0.08)
        axis.loglog(stiffness, [r.observed for r in mine], "o", color=colour,
                    label=f"{method}: observed ({mine[0].how})")
    axis.set_xlabel("spring stiffness (N/m), 1 kg block, damping ratio 0.2")
    axis.set_ylabel("largest stable step (s)")
    axis.set_title("Explicit methods: predicted (band: factor 2) and observed stable steps",
                   fontsize=10)
    axis.grid(True, which="both", alpha=0.3)
    axis.legend(fontsize=7)
    return figure


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
    status: str  # "finished", "failed", "diverged"
    reason: str
    steps: int
    rejected: int
    cpu_time: float
    position_drift: float
    velocity_drift: float
    energy_error: float | None
    error: float | None
    condition_max: float
    sigma_min: float
    redundant_rows: list[str]
    accurate: bool

    def as_dict(self) -> dict:
        return asdict(self)


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
    data = Data()
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


def _diverged(result: SimulationResult) -> str:
    """Why a finished run is not to be believed: non-finite or runaway states."""
    if not (np.all(np.isfinite(result.q)) and np.all(np.isfinite(result.v))):
        return "the state became non-finite"
    speed = np.abs(result.v).max(axis=1)
    if speed[-1] > 1e3 * max(speed[0], np.median(speed), 1e-3):
        return f"speeds grew from {speed[0]:.3g} to {speed[-1]:.3g} (unstable step)"
    return ""


def run_case(case: SuiteCase, method: str, *, budget: float = 60.0) -> CaseRun:
    """One method on one case, at the case's setting for it."""
    setting = _setting(case, method)
    result = simulate(case.model, case.t_end, method=method, forces=False, cpu_budget=budget,
                      **setting)
    status, reason = result.status, result.message
    if result.success:
        why = _diverged(result)
        if why:
            status, reason = "diverged", why
    conserved = result.energy_drift if case.model.energy_conserved else None
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
                   result.counters.steps, result.counters.rejected, result.cpu_time,
                   result.max_position_violation, result.max_velocity_violation, conserved,
                   error, condition, sigma, redundant, accurate)


def run_suite(cases: list[SuiteCase], methods=None, *, budget: float = 60.0,
              progress: Callable[[str], None] | None = None) -> list[CaseRun]:
    """Every method (default: the registry) on every case."""
    runs = []
    for case in cases:
        for method in methods or INTEGRATORS:
            if progress:
                progress(f"{case.name}: {method}")
            started = time.perf_counter()
            runs.append(run_case(case, method, budget=budget))
            if progress:
                run = runs[-1]
                progress(f"{case.name}: {method} {run.status}"
                         f"{' (accurate)' if run.accurate else ''} in "
                         f"{time.perf_counter() - started:.1f} s")
    return runs


def recommend(runs: list[CaseRun]) -> str:
    """The method to use on one case: the cheapest accurate run; else the most accurate."""
    good = sorted((r for r in runs if r.accurate), key=lambda r: r.cpu_time)
    if good:
        best = good[0]
        others = ", ".join(r.method for r in good[1:4])
        return (f"{best.method} ({best.cpu_time:.3g} s)"
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
    lines = ["| case | method | setting | outcome | steps | rejected | CPU (s) | drift | "
             "energy error | error | max cond | min sigma |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for case in dict.fromkeys(r.case for r in runs):
        mine = [r for r in runs if r.case == case]
        for r in mine:
            outcome = r.status + (", accurate" if r.accurate else "")
            if r.status != "finished":
                outcome += ": " + r.reason.split(": ", 1)[-1][:90]
            lines.append(
                f"| {case} | {r.method} | {r.setting} | {outcome} | {r.steps} | {r.rejected} | "
                f"{r.cpu_time:.3g} | {_number(r.position_drift)} | {_number(r.energy_error)} | "
                f"{_number(r.error)} | {_number(r.condition_max)} | {_number(r.sigma_min)} |")
        lines.append(f"| **{case}** | **use** | | {recommend(mine)} | | | | | | | | |")
    return "\n".join(lines)


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


def runs_csv(runs: list[CaseRun]) -> str:
    buffer = io.StringIO()
    fields = list(CaseRun.__dataclass_fields__)
    writer = csv.DictWriter(buffer, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    for r in runs:
        row = r.as_dict()
        row["redundant_rows"] = " ".join(row["redundant_rows"])
        writer.writerow(row)
    return buffer.getvalue()


def outcome_figure(runs: list[CaseRun]):
    """Cases against methods: green accurate, yellow finished but inaccurate, red failed or
    diverged; each cell gives the CPU time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    cases = list(dict.fromkeys(r.case for r in runs))
    methods = list(dict.fromkeys(r.method for r in runs))
    grid = np.full((len(cases), len(methods)), np.nan)
    figure, axis = plt.subplots(figsize=(1.3 * len(methods) + 2.5, 0.42 * len(cases) + 1.6),
                                layout="constrained")
    for r in runs:
        i, j = cases.index(r.case), methods.index(r.method)
        grid[i, j] = 2 if r.accurate else (1 if r.status == "finished" else 0)
        axis.text(j, i, f"{r.cpu_time:.2g} s" if r.status == "finished" else r.status,
                  ha="center", va="center", fontsize=7)
    axis.imshow(grid, cmap=ListedColormap(["#f4a6a6", "#f6e3a1", "#b7e4b0"]), vmin=0, vmax=2,
                aspect="auto")
    axis.set_xticks(range(len(methods)), methods, rotation=30, ha="right", fontsize=8)
    axis.set_yticks(range(len(cases)), cases, fontsize=8)
    axis.set_title("green: accurate; yellow: finished, not accurate; red: failed or diverged "
                   "(CPU time in the cell)", fontsize=9)
    return figure


def condition_figure(results: dict[str, tuple[Model, SimulationResult]]):
    """The condition number of the equilibrated saddle-point matrix and the smallest singular
    value of the equilibrated Phi_v along runs (one line per case)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, (top, bottom) = plt.subplots(2, 1, figsize=(7.0, 5.6), sharex=True,
                                         layout="constrained")
    data = Data()
    for name, (model, result) in results.items():
        cond, sigma = [], []
        for t, q, v in zip(result.t, result.q, result.v, strict=True):
            forward_dynamics(model, data, float(t), q, v, condition=True)
            cond.append(data.condition_number)
            sigma.append(data.sigma_min)
        fraction = result.t / result.t[-1]
        top.semilogy(fraction, cond, label=name)
        bottom.semilogy(fraction, sigma, label=name)
    top.set_ylabel("condition number")
    bottom.set_ylabel("smallest singular value")
    bottom.set_xlabel(f"fraction of the run ({DEFAULT_METHOD})")
    top.set_title("Along the singular and redundant cases", fontsize=10)
    for axis in (top, bottom):
        axis.grid(True, which="both", alpha=0.3)
    top.legend(fontsize=7)
    return figure
