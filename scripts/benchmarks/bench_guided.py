"""What following guides costs: a guided scene's inverse dynamics, and the part of it that solves
the guides' kinematics, in one process.

A guided run solves the guides' kinematics (the motion alone: positions, velocities and
accelerations by :func:`hexapod.algorithms.prescribed.prescribed_motion`, no multipliers,
policy or wrenches) and then the dynamics of its twin, whose guided joints are driven by the
motion found: the run of the same motion given joint by joint. For each scene (default: the
walking robot ``hexapod`` and the ``front-leg``), over one stride of ``--samples`` samples:

* ``first``: CPU of the first run of a freshly assembled model (what a command pays: the
  plans of its rank decisions built), and of its kinematics, up to the progress report of its
  last sample (the first half of the run's progress);
* ``again``: the least CPU of ``--repeats`` later runs of the same model (the evaluation).

The share of the kinematics is what a guided run costs over the same motion given joint by
joint. Evaluated by CasADi's virtual machine (the library's default); one BLAS thread.

    python3 scripts/benchmarks/bench_guided.py [--scenes hexapod front-leg] [--samples 501]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from measure import load_average, one_blas_thread

one_blas_thread()

import hexapod as hx  # noqa: E402


def _run(model, times) -> tuple[float, float]:
    """CPU of the whole guided run, and of its kinematics (up to the progress report of the
    kinematics' last sample, the first half of the run's)."""
    start = time.process_time()
    kinematics = []

    def progress(done: int, total: int) -> None:
        if 2 * done <= total:
            kinematics.append(time.process_time() - start)

    hx.inverse_dynamics(model, times, progress=progress)
    return time.process_time() - start, kinematics[-1]


def measure(scene_name: str, samples: int, repeats: int) -> dict[str, tuple[float, float]]:
    model = hx.assemble(hx.load_scene(scene_name))
    times = np.linspace(0.0, model.time_window(None)[0], samples)  # one stride
    first = _run(model, times)
    again = min((_run(model, times) for _ in range(repeats)), key=lambda run: run[0])
    return {"first": first, "again": again}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenes", nargs="+", default=["hexapod", "front-leg"])
    parser.add_argument("--samples", type=int, default=501)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    print(f"load average {load_average()}; {args.samples} samples of a stride; CPU s")
    print("| scene | first run: guided | of which the kinematics | again: guided | of which "
          "the kinematics |")
    print("| --- | --- | --- | --- | --- |")
    for name in args.scenes:
        m = measure(name, args.samples, args.repeats)
        cells = [f"{m[run][0]:.3f} | {m[run][1]:.3f} ({m[run][1] / m[run][0]:.0%})"
                 for run in ("first", "again")]
        print(f"| {name} | {' | '.join(cells)} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
