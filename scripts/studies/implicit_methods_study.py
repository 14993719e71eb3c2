"""The implicit and geometric methods on the cases where they failed: measured, case by case.

    python scripts/studies/implicit_methods_study.py                  # all parts, about ten minutes
    python scripts/studies/implicit_methods_study.py --parts pendulum andrews

Parts (each a table on standard output; nothing is written):

* ``pendulum``: generalized-alpha on the pendulum released horizontal (``long_pendulum``, 100
  periods) at 20 and 40 steps per period: outcome, largest energy error over the first and the
  last 10 periods (relative to the largest kinetic energy, ``m g l / 2``), constraint residuals.
* ``bricard``: every method on Bricard's mechanism over 10 s, at its defaults and at the settings
  that failed before (generalized-alpha h = 1e-2, 5e-3; RATTLE h = 1.25e-3, 1e-3; Radau5-GGL
  rtol = atol = 1e-4, 1e-6).
* ``four-bar``: every method on the spatial N-four-bar (N = 2, six redundant rows) released from
  rest 45 degrees from hanging down, over 10 s; the error against the crank angle's equation.
* ``standing``: every method on the hexapod standing on six feet (``hexapod-standing``) over 2 s
  (fixed steps of 2e-3 s, as ``hexapod check``): its exact motion is rest.
* ``n-four-bar``: generalized-alpha, RATTLE, Radau5-GGL and IDAS on ``n_four_bar(10, t_end=10)``
  through its flat poses: crossed (error against the reference) or stopped (the message).
* ``andrews``: Radau5-GGL and IDAS on Andrews' squeezer at rtol = atol = 1e-10 to 1e-13 against
  the Test Set's y(0.03).

Each run is stopped after ``--cpu-budget`` CPU seconds of its time loop.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import hexapod as hx
from hexapod import INTEGRATORS, body_poses, consistent_state, load_scene
from hexapod import benchmarks as m
from hexapod.benchmarks import andrews_problem

ROOT = Path(__file__).resolve().parents[2]
G = 9.81
PARTS = ("pendulum", "bricard", "four-bar", "standing", "n-four-bar", "andrews")


def run(model, t_end, method, budget, **options):
    start = time.process_time()
    result = hx.simulate(model, t_end, method=method, forces=False, cpu_budget=budget, **options)
    return result, time.process_time() - start


def outcome(result) -> str:
    return result.status if result.success else f"{result.status} at t = {result.t[-1]:.4g} s"


def label(options: dict) -> str:
    return ", ".join(f"{k} {v:g}" for k, v in options.items()) or "defaults"


def pendulum(budget: float) -> None:
    periods = 100
    case = m.long_pendulum(periods=periods)
    model = hx.assemble(case.scene)
    period = case.t_end / periods
    print("| steps per period | outcome | energy error, first 10 periods | last 10 periods "
          "| phi | velocity residual | CPU (s) |\n|---|---|---|---|---|---|---|")
    for count in (20, 40):
        result, cpu = run(model, case.t_end, "generalized-alpha", budget, step=period / count)
        error = np.abs(result.energy - result.energy[0]) / (G * 0.5)
        first = error[result.t <= 10 * period].max()
        last = error[result.t >= result.t[-1] - 10 * period].max()
        print(f"| {count} | {outcome(result)} | {first:.2e} | {last:.2e} "
              f"| {result.max_position_violation:.1e} | {result.max_velocity_violation:.1e} "
              f"| {cpu:.1f} |", flush=True)


def table_header() -> None:
    print("| method | setting | outcome | error | phi | velocity residual | energy drift | steps "
          "| rejected | CPU (s) |\n|---|---|---|---|---|---|---|---|---|---|")


def table_row(method, options, result, error, cpu) -> None:
    drift = "-" if result.energy_drift is None else f"{result.energy_drift:.1e}"
    print(f"| {method} | {label(options)} | {outcome(result)} | "
          + ("-" if error is None else f"{error:.1e}")
          + f" | {result.max_position_violation:.1e} | {result.max_velocity_violation:.1e} | "
          f"{drift} | {result.counters.steps} | {result.counters.rejected} | {cpu:.2f} |",
          flush=True)


def bricard(budget: float) -> None:
    case = m.bricard()
    model = hx.assemble(case.scene)
    failed = {"generalized-alpha": [{"step": 1e-2}, {"step": 5e-3}],
              "rattle": [{"step": 1.25e-3}, {"step": 1e-3}],
              "radau5-ggl": [{"rtol": 1e-4, "atol": 1e-4}, {"rtol": 1e-6, "atol": 1e-6}]}
    table_header()
    for method in INTEGRATORS:
        for options in [{}] + failed.get(method, []):
            result, cpu = run(model, case.t_end, method, budget, **options)
            error = case.error(model, result.t, result.q) if result.success else None
            table_row(method, options, result, error, cpu)


def four_bar(budget: float) -> None:
    case = m.n_four_bar(2, t_end=10.0, dimension=3, start_angle=3 * np.pi / 4, start_rate=0.0)
    model = hx.assemble(case.scene)
    table_header()
    for method in INTEGRATORS:
        result, cpu = run(model, case.t_end, method, budget)
        error = (np.abs(case.observable(model, result.q) - case.reference(result.t)).max()
                 / case.length)
        table_row(method, {}, result, error, cpu)


def standing(budget: float) -> None:
    model = hx.assemble(load_scene("hexapod-standing"))
    start = body_poses(model, consistent_state(model, model.create_data())[0])[0]
    table_header()
    for method in INTEGRATORS:
        options = {} if INTEGRATORS[method].adaptive else {"step": 2e-3}
        result, cpu = run(model, 2.0, method, budget, **options)
        moved = np.abs(body_poses(model, result.q)[0] - start).max()
        # at rest the loop's drift is relative to a kinetic energy of zero: the energy change
        # relative to m g L instead
        weight = sum(b.mass for b in model.bodies) * G * model.characteristic_length
        result.energy_drift = float(np.abs(result.energy - result.energy[0]).max() / weight)
        table_row(method, options, result, moved / model.characteristic_length, cpu)


def n_four_bar(budget: float) -> None:
    case = m.n_four_bar(10, t_end=10.0)
    model = hx.assemble(case.scene)
    print("| method | outcome | error up to the end | CPU (s) | message |\n|---|---|---|---|---|")
    for method in ("generalized-alpha", "rattle", "radau5-ggl", "idas-bdf"):
        result, cpu = run(model, case.t_end, method, budget)
        error = case.error(model, result.t, result.q)
        print(f"| {method} | {outcome(result)} | {error:.1e} | {cpu:.1f} | {result.message} |",
              flush=True)


def andrews(budget: float) -> None:
    problem = andrews_problem(ROOT / "data")
    print("| method | rtol = atol | outcome | error at 0.03 s | steps | CPU (s) |\n"
          "|---|---|---|---|---|---|")
    for method in ("radau5-ggl", "idas-bdf"):
        for tol in (1e-10, 1e-11, 1e-12, 1e-13):
            result, cpu = run(problem.model, problem.t_end, method, budget, rtol=tol, atol=tol)
            error = f"{problem.error(result):.1e}" if result.success else "-"
            print(f"| {method} | {tol:.0e} | {outcome(result)} | {error} | "
                  f"{result.counters.steps} | {cpu:.2f} |", flush=True)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--parts", nargs="+", choices=PARTS, default=list(PARTS))
    parser.add_argument("--cpu-budget", type=float, default=120.0, metavar="S")
    args = parser.parse_args(argv)
    for part in args.parts:
        print(f"\n## {part}\n")
        globals()[part.replace("-", "_")](args.cpu_budget)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    raise SystemExit(main())
