"""Per-sample cost of the compiled closed-loop inverse dynamics (the phase path) against the tree
path, on the hexapod.

Protocol
--------
* Scenes (built-in): ``hexapod-held`` (the robot with its trunk welded to the world: an open
  driven tree, the tree path), ``hexapod`` (the walking robot: a free trunk, feet in stance held
  by contacts, ground forces by the least-wrench policy: the phase path) and
  ``hexapod-standing`` (six feet pinned, every joint held: 12 redundant rows, the phase path).
* Motion: one stride, ``--samples`` samples over 0.5 s (default 5001).
* Build: what the first call of ``inverse_dynamics(model, times)`` under
  ``hx.executing(compiled=True)`` costs more than the later ones (assembly apart): building
  the CasADi Functions and compiling them to C with gcc, in wall time and in CPU time of this
  process and of the compiler it starts. Compiled code is kept with the model, so the later
  calls only evaluate it.
* Per sample: ``time.process_time`` of the later calls (the median of ``--repeats``), over the
  number of samples, each on the times moved by a picosecond so that no law reuses values kept
  from the call before. This is what a
  user pays per sample on a long motion: the law values (evaluated in NumPy), the compiled
  evaluation, and for the phase path its exact first sample and its rank decisions (one per
  contact set).
  The laws' own cost is printed apart, and the ratios with and without it (the held robot's
  laws are harmonic series, the walking robot's the gait's exact inverse kinematics, the
  standing robot's constants).
* The phase path interpreted by CasADi's virtual machine (the library's default), on a fresh
  model: one call, its build apart.
* The saddle path (every sample solved exactly in Python: the reference) on ``--saddle``
  samples (default 6) from 0.195 s to 0.205 s of the same stride (a touch-down of the walking
  robot at 0.2 s).
* Agreement: the largest difference between the phase and the saddle path on those samples
  (forces, moments, efforts, ground forces), relative to the largest magnitude of each.

Timings are noisy on a shared machine: compare the ratios of one run.

    python3 scripts/benchmarks/bench_closed_loop.py [--samples 5001] [--repeats 3] [--saddle 6]
"""

from __future__ import annotations

import argparse
import time

from measure import cpu_seconds, log, median_time, one_blas_thread, start

one_blas_thread()  # before NumPy loads

import numpy as np  # noqa: E402

import hexapod as hx  # noqa: E402

STRIDE = 0.5  # s


def _timed(model, times, repeats: int, compiled: bool = False,
           **options) -> tuple[float, float, float, object]:
    """The first call's wall and CPU seconds, the later calls' CPU seconds per sample (median),
    and the result, compiled or not. Each later call moves the times by a picosecond, so that
    no law reuses values kept from the call before (the walking robot's gait laws keep their
    last samples)."""
    with hx.executing(compiled=compiled):
        return _calls(model, times, repeats, **options)


def _calls(model, times, repeats: int, **options) -> tuple[float, float, float, object]:
    wall, cpu = time.perf_counter(), cpu_seconds()
    result = hx.inverse_dynamics(model, times, **options)
    first_wall, first_cpu = time.perf_counter() - wall, cpu_seconds() - cpu
    results = [result]

    def later(k: int) -> None:
        results.append(hx.inverse_dynamics(model, times + (k + 1) * 1e-12, **options))
    cost = median_time(later, repeats)
    return first_wall, first_cpu, cost / times.size, results[-1]


def _laws(model, times, repeats: int) -> float:
    """CPU seconds per sample of the law values, on times moved by picoseconds as in
    :func:`_timed` but the other way: the walking robot's gait laws keep the samples of the
    calls before, and on :func:`_timed`'s own times they cost nothing (1 us a sample)."""
    return median_time(lambda k: model.law_values(times - (k + 1) * 1e-12), repeats) / times.size


def _agreement(a, b) -> float:
    worst = 0.0
    for key in ("force", "torque", "effort", "ground_force"):
        x, y = getattr(a, key), getattr(b, key)
        if x is None or x.size == 0:
            continue
        scale = np.nanmax(np.abs(y)) or 1.0
        worst = max(worst, float(np.nanmax(np.abs(x - y)) / scale))
    return worst


def run(name: str, times, args) -> dict:
    model = hx.assemble(hx.load_scene(name))
    wall, cpu, cost, result = _timed(model, times, args.repeats, compiled=True)
    steady = cost * times.size
    row = {"scene": name, "method": result.method, "build_wall": wall - steady,
           "build_cpu": cpu - steady, "us": 1e6 * cost,
           "laws_us": 1e6 * _laws(model, times, args.repeats)}
    if result.method == "phase":
        interpreted = hx.assemble(hx.load_scene(name))  # a model without compiled code
        wall, _, cost, _ = _timed(interpreted, times, 1)
        row["vm_build"], row["vm_us"] = wall - cost * times.size, 1e6 * cost
        few = np.linspace(0.195, 0.205, args.saddle)  # across a touch-down at 0.2 s
        _, _, saddle, exact = _timed(model, few, 1, method="saddle")
        with hx.executing(compiled=True):
            phase = hx.inverse_dynamics(model, few, method="phase")
        row["saddle_us"] = 1e6 * saddle
        row["agreement"] = _agreement(phase, exact)
    log(f"  {name}: done")
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=5001)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--saddle", type=int, default=6, help="samples of the saddle path")
    args = parser.parse_args()
    times = np.linspace(0.0, STRIDE, args.samples)
    rows = [run(name, times, args) for name in ("hexapod-held", "hexapod", "hexapod-standing")]
    tree = rows[0]
    print(f"{args.samples} samples over {STRIDE} s; CPU per sample in microseconds (median of "
          f"{args.repeats}); build in seconds (wall, and CPU with the compiler's)")
    print(f"{'scene':<18}{'method':>7}{'build wall':>11}{'build cpu':>10}{'per sample':>11}"
          f"{'laws':>8}{'ratio':>7}{'w/o laws':>9}{'interp.':>9}{'saddle':>10}{'agreement':>11}")
    for row in rows:
        ratio = row["us"] / tree["us"]
        bare = (row["us"] - row["laws_us"]) / (tree["us"] - tree["laws_us"])
        saddle = f"{row['saddle_us']:>10.0f}" if "saddle_us" in row else f"{'-':>10}"
        vm = f"{row['vm_us']:>9.0f}" if "vm_us" in row else f"{'-':>9}"
        agree = f"{row['agreement']:>11.1e}" if "agreement" in row else f"{'-':>11}"
        print(f"{row['scene']:<18}{row['method']:>7}{row['build_wall']:>11.1f}"
              f"{row['build_cpu']:>10.1f}{row['us']:>11.1f}{row['laws_us']:>8.1f}"
              f"{ratio:>7.2f}{bare:>9.2f}{vm}{saddle}{agree}")
    print("ratio: per sample against hexapod-held (tree path), target <= 3; w/o laws: the "
          "same without the law values' cost; interp.: the phase path in CasADi's interpreter "
          "(the default execution), per sample; saddle: the exact path, per sample")


if __name__ == "__main__":
    start("bench_closed_loop")
    main()
