"""The runs of ``scripts/benchmarks/bench_forward.py``: one run of a hexapod integrator, the best of
several, the walk along a ladder of tolerances or steps, and the CPU time to the target error
interpolated between the rungs."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from bench_forward_problems import Reference, position_indices

import hexapod as hx
from hexapod import get_integrator

TARGET = 1e-6  # relative position error of (b)
REPRESENTATIVE_RTOL = 1e-6
REPRESENTATIVE_STEP = 1e-3  # s
RTOL_LADDER = [10.0**-k for k in range(3, 12)]  # loose -> tight
STEP_LADDER = [4e-3 / 2**k for k in range(12)]  # 4 ms ... 2 us, loose -> tight
LONG_RUN = 10.0  # s of CPU: such a run is not repeated


@dataclass
class Run:
    """One run of one method at one setting."""

    setting: float
    cpu: float = float("inf")
    steps: int = 0
    error: float = float("inf")
    status: str = "not run"
    message: str = ""
    counters: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.status == "finished" and np.isfinite(self.error)

    def as_dict(self) -> dict:
        return {"setting": self.setting, "cpu_s": self.cpu, "steps": self.steps,
                "cpu_per_step_ms": self.per_step_ms, "error": self.error,
                "status": self.status, "message": self.message, "counters": self.counters}

    @property
    def per_step_ms(self) -> float:
        return 1e3 * self.cpu / self.steps if self.steps else float("nan")


def run_hexapod(model: hx.Model, method: str, setting: float, t_end: float, ref: Reference,
                budget: float) -> Run:
    cls = get_integrator(method)
    kwargs = {"rtol": setting, "atol": setting} if cls.adaptive else {"step": setting}
    q_index, _ = position_indices(model)
    times, positions = [0.0], [model.q0[q_index]]
    cpu = time.process_time()
    integrator = cls(model, 0.0, t_end, **kwargs)
    while integrator.status == "running":
        integrator.step()
        times.append(integrator.t)
        positions.append(integrator.q[q_index])
        if time.process_time() - cpu > budget:
            integrator.status, integrator.message = "budget", f"stopped at t = {integrator.t:.4g} s"
            break
    cpu = time.process_time() - cpu
    run = Run(setting, cpu, integrator.counters.steps, status=integrator.status,
              message=integrator.message, counters=integrator.counters.as_dict())
    if run.status == "finished":
        run.error = ref.error(np.array(times), np.array(positions))
    return run


def best_of(repeat: int, once: Callable[[], Run]) -> Run:
    """The run with the least CPU time of ``repeat`` (one when a run is long or fails)."""
    best = once()
    for _ in range(repeat - 1):
        if not best.ok or best.cpu > LONG_RUN:
            break
        again = once()
        if again.cpu < best.cpu:
            best = again
    return best


# ------------------------------------------------------------------ the ladder and (b)

def walk(ladder: list[float], start: int, run: Callable[[float], Run], growth: float,
         budget: float) -> dict[int, Run]:
    """Run rungs from ``start``: tighter while the error is above the target, looser while
    below; stop at the bracket, the ladder's end, or the budget. ``growth``: the expected
    factor of CPU time from one rung to the next tighter one (to skip a rung predicted to
    exceed the budget)."""
    runs: dict[int, Run] = {}
    first = runs[start] = run(ladder[start])
    # looser from a run that reached the target or was stopped by the budget, else tighter
    looser = (first.ok and first.error <= TARGET) or first.status == "budget"
    direction = -1 if looser else 1
    i = start
    while 0 <= i + direction < len(ladder):
        previous = runs[i]
        i += direction
        if direction == 1 and previous.cpu * growth > budget:
            runs[i] = Run(ladder[i], status="skipped",
                          message=f"predicted {previous.cpu * growth:.0f} s > budget")
            break
        current = runs[i] = run(ladder[i])
        if direction == 1 and current.ok and current.error <= TARGET:
            break
        if direction == -1 and current.status != "budget" and not (
                current.ok and current.error <= TARGET):
            break
    return runs


def bracket(runs: dict[int, Run]) -> list[int]:
    """The rungs :func:`time_to_target` reads: the loosest that reaches ``TARGET`` and, when
    the rung before it ran and did not, that one first (none when no rung reaches it)."""
    below = [i for i, r in sorted(runs.items()) if r.ok and r.error <= TARGET]
    if not below:
        return []
    i = min(below)
    loose = runs.get(i - 1)
    return [i - 1, i] if loose is not None and loose.ok and loose.error > TARGET else [i]


def time_to_target(runs: dict[int, Run]) -> tuple[float, str]:
    """CPU time to reach ``TARGET``: (value, qualifier '=', '<=' or '>')."""
    rungs = bracket(runs)
    if not rungs:
        finished = [r.cpu for _, r in sorted(runs.items()) if r.status in ("finished", "budget")]
        return (max(finished), ">") if finished else (float("nan"), "")
    if len(rungs) == 1:
        return runs[rungs[0]].cpu, "<="
    loose, tight = runs[rungs[0]], runs[rungs[1]]
    x = (np.log(TARGET) - np.log(loose.error)) / (np.log(tight.error) - np.log(loose.error))
    return float(np.exp(np.log(loose.cpu) + x * (np.log(tight.cpu) - np.log(loose.cpu)))), "="


def runs_of(entry: dict, ladder: list[float]) -> dict[int, Run]:
    """The runs of a method's entry in the results (its ``rungs``), by their place in
    ``ladder``."""
    return {ladder.index(d["setting"]): Run(d["setting"], d["cpu_s"], d["steps"], d["error"],
                                            d["status"], d["message"], d["counters"])
            for d in entry["rungs"]}
