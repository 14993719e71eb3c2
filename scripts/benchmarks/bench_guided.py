"""The walking robot guided by its feet against the built-in robot on its joint laws: the same
numbers, and what the guides cost.

Protocol
--------
* The built-in ``hexapod`` (free trunk, tripod, min-wrench) and the same robot with each foot's
  path as guides in the trunk's frame and the three joints per leg that the cockroach's own
  inverse kinematics solves following them (``legs.robot.hexapod_scene(..., guided=True)``:
  the engine's Newton solve places the legs). One stride at ``--samples`` samples (default
  501, the report's).
* Agreement: the largest difference of every effort, joint force and moment, ground force and
  position, over the largest value of each. Target: 1e-9 (the robot issue's bar for the
  cockroach through the general path). A miss ends with status 1.
* Cost: CPU time (``time.process_time``) of ``hx.inverse_dynamics`` per sample, the median of
  ``--repeats`` calls after a warm-up call, both robots alternately in one process; and the
  first call of each (its assembly and builds). The guided run is two runs (the guides'
  kinematics, then the joints' dynamics), so its ratio says what merging them would gain.

Everything stays in memory (hexapod's cache in a scratch folder); nothing is written.

    python3 scripts/benchmarks/bench_guided.py [--samples 501] [--repeats 3]
"""

from __future__ import annotations

import argparse
import sys
import time

import measure

measure.one_blas_thread()

import numpy as np  # noqa: E402

import hexapod as hx  # noqa: E402
from legs.robot import hexapod_scene  # noqa: E402

TOLERANCE = 1e-9
QUANTITIES = ("effort", "force", "torque", "ground_force", "q")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=501)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    measure.start("bench_guided")
    scenes = {"joint laws": hexapod_scene("tripod", trunk="free"),
              "guided": hexapod_scene("tripod", trunk="free", guided=True)}
    times = np.linspace(0.0, 0.5, args.samples)
    models, results, first = {}, {}, {}
    for name, scene in scenes.items():
        tic = time.process_time()
        models[name] = hx.assemble(scene)
        results[name] = hx.inverse_dynamics(models[name], times)
        first[name] = time.process_time() - tic
    costs = {name: [] for name in scenes}
    for k in range(args.repeats):
        for name, model in models.items():
            tic = time.process_time()
            hx.inverse_dynamics(model, times + 1e-12 * (k + 1))
            costs[name].append(time.process_time() - tic)
    print(f"walking robot, one stride, {args.samples} samples ({measure.load_average()})")
    print("| robot | first call (s) | per sample (us) | path |")
    print("| --- | ---: | ---: | --- |")
    for name in scenes:
        per_sample = 1e6 * float(np.median(costs[name])) / args.samples
        print(f"| {name} | {first[name]:.2f} | {per_sample:.0f} | {results[name].method} |")
    ratio = float(np.median(costs["guided"]) / np.median(costs["joint laws"]))
    print(f"guided / joint laws: {ratio:.2f}")
    worst = 0.0
    for quantity in QUANTITIES:
        a, b = (getattr(results[name], quantity) for name in ("guided", "joint laws"))
        error = float(np.nanmax(np.abs(a - b)) / np.nanmax(np.abs(b)))
        worst = max(worst, error)
        print(f"{quantity}: largest difference {error:.1e} of the largest value")
    if not worst <= TOLERANCE:
        print(f"agreement {worst:.1e} misses {TOLERANCE:.0e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
