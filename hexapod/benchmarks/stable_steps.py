"""The largest stable step of the explicit methods on stiff springs, predicted and observed.

For a 1 kg block on a spring-damper of stiffness 1e3 .. 1e9 N/m, the largest stable step predicted
by :func:`hexapod.simulation.diagnostics.diagnose` (the method's stability region along the
linearised modes) against the one observed: for fixed-step methods the largest step whose run
does not gain energy (bisection), for adaptive ones the median step their controller settles on
once the motion has died out (the controller then works at the edge of the stability region:
Hairer and Wanner, *Solving ODEs II*, IV.2). Part of ``hexapod check``
(:mod:`hexapod.benchmarks.check`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np

from hexapod.algorithms.kinematics import consistent_state
from hexapod.model.model import Model
from hexapod.simulation.diagnostics import diagnose
from hexapod.simulation.loop import simulate
from hexapod.simulation.registry import INTEGRATORS


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


#: ``stability.csv``: one row per :class:`StabilityRow` (``as_dict``), column -> (unit, meaning).
STABILITY_COLUMNS = {"stiffness": ("N/m", "stiffness of the spring"),
                     "method": (None, "the explicit integrator"),
                     "predicted": ("s", "largest stable step predicted"),
                     "observed": ("s", "largest stable step observed"),
                     "how": (None, "bisection (fixed step) or median step (adaptive)"),
                     "ratio": ("1", "observed over predicted")}


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


#: damping ratio of the stiff springs of the stability study: enough for a stable step to lose
#: energy within a few hundred steps, little enough to keep the modes oscillatory
DAMPING_RATIO = 0.2


def stiff_spring(stiffness: float):
    """The scene of the stability study: :func:`hexapod.benchmarks.stiff.stiff_slider` (1 kg,
    released 10 mm from rest) without gravity, at damping ratio :data:`DAMPING_RATIO`."""
    from hexapod.benchmarks.stiff import stiff_slider

    damping = 2 * DAMPING_RATIO * np.sqrt(stiffness)
    return stiff_slider(stiffness, damping, gravity=False).scene


def explicit_methods() -> list[str]:
    """The registered methods with a stability limit (explicit ones)."""
    return [name for name, cls in INTEGRATORS.items()
            if cls.largest_stable_step([1j]) is not None]


def stability_study(scene_of: Callable[[float], object], stiffnesses=(1e3, 1e5, 1e7, 1e9),
                    methods=None, progress: Callable[[str], None] | None = None,
                    assemble: Callable | None = None) -> list[StabilityRow]:
    """Predicted and observed largest stable steps of the explicit ``methods`` on the scenes
    ``scene_of(stiffness)`` (damped, released away from rest)."""
    from hexapod.algorithms.assembly import assemble as default_assemble

    build = assemble or default_assemble
    rows = []
    for k in stiffnesses:
        model = build(scene_of(k))
        data = model.create_data()
        q, v = consistent_state(model, data)
        diagnosis = diagnose(model, data, 0.0, q, v, methods=methods or explicit_methods(),
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
    from matplotlib.figure import Figure

    figure = Figure(figsize=(7.0, 4.6), layout="constrained")
    axis = figure.subplots()
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


