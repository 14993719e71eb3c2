"""Forward simulation of the walking robot: CPU per simulated second, and where it goes.

Protocol
--------
* Model: the built-in ``hexapod`` scene (the free-trunk robot of ``legs``, its 36 joints on the
  tripod gait's laws, the feet held by the contact schedule), assembled once.
* Runs, in one process, one after the other: ``hexapod.simulate`` over ``--strides`` strides
  from ``t = 0`` by ``--method`` (default: the library's, ``dop853-projection``) at
  ``rtol = 1e-6`` (the defaults), (a) as the command line runs it, the gait laws tabulated
  once and interpolated (:mod:`hexapod.model.tabulation`), every step's state saved, and (b) with
  ``exact_laws=True``, every law solved at every stage, stopped by ``--budget`` CPU seconds
  (default 60) and counted per simulated second up to where it got. Each run starts from a
  fresh assembly, so that neither reuses what the other built; the set-up (the table, the
  consistent start, the first kernels) is timed apart.
* Figures: CPU seconds of the time loop per simulated second (``cpu_time`` of the result:
  the steps, saves and the kernels built at contact changes), steps and right-hand sides per
  simulated second, CPU per right-hand side, and the table's grid and errors. The ratio exact /
  tabulated is the speed-up; the target of the project is 1 s of CPU per simulated second.
* Agreement: the exact laws' run saves its states at the times of the first's steps (from
  its method's dense output, which does not change its steps); the largest difference of the
  coordinates at the times both reached, against the table's error and the run's tolerance.
* Prints a Markdown table on stdout; progress and the load average on stderr. Writes nothing.

    python3 scripts/benchmarks/bench_walking_forward.py [--strides 1] [--budget 60]
"""

from __future__ import annotations

import argparse
import time

from measure import log, one_blas_thread, start

one_blas_thread()  # before NumPy loads

import numpy as np  # noqa: E402

import hexapod as hx  # noqa: E402


def _run(label: str, t_end: float, method: str, budget: float, exact: bool,
         t_eval: np.ndarray | None = None) -> dict:
    model = hx.assemble(hx.load_scene("hexapod"))
    log(f"{label}: simulating {t_end:g} s")
    tic = time.process_time()
    result = hx.simulate(model, t_end, method=method, exact_laws=exact, cpu_budget=budget,
                         t_eval=t_eval)
    set_up = time.process_time() - tic - result.cpu_time  # the start: table, state, kernels
    reached = float(result.t_reached if result.t_reached is not None else result.t[-1])
    counters = result.counters
    return {"label": label, "status": result.status, "reached": reached,
            "cpu": result.cpu_time, "per_second": result.cpu_time / reached,
            "steps": counters.steps / reached, "rhs": counters.rhs / reached,
            "per_rhs": result.cpu_time / max(counters.rhs, 1), "set_up": set_up,
            "laws": result.options.get("laws"), "t": result.t, "q": result.q}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--strides", type=float, default=1.0)
    parser.add_argument("--method", default=hx.simulation.DEFAULT_METHOD)
    parser.add_argument("--budget", type=float, default=60.0,
                        help="CPU seconds for the run with exact laws")
    args = parser.parse_args()
    start("bench_walking_forward")
    stride = hx.assemble(hx.load_scene("hexapod")).cycle_time()
    t_end = args.strides * stride
    fast = _run("tabulated laws", t_end, args.method, 10 * args.budget, exact=False)
    # the exact laws' run saves its states at the steps of the first (its dense output)
    runs = [fast, _run("exact laws", t_end, args.method, args.budget, exact=True,
                       t_eval=fast["t"][1:])]
    print(f"\nWalking robot, {args.method}, rtol 1e-6, {t_end:g} s ({args.strides:g} stride)\n")
    print("| laws | status | reached s | CPU s per simulated s | steps per s | rhs per s | "
          "CPU per rhs ms | set-up s |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in runs:
        print(f"| {r['label']} | {r['status']} | {r['reached']:.3g} | {r['per_second']:.3g} | "
              f"{r['steps']:.0f} | {r['rhs']:.0f} | {1e3 * r['per_rhs']:.3g} | "
              f"{r['set_up']:.2f} |")
    fast, exact = runs
    print(f"\nSpeed-up of the time loop: {exact['per_second'] / fast['per_second']:.1f} times "
          f"(target: 1 s of CPU per simulated second; now {fast['per_second']:.2g} s)")
    laws = fast["laws"]
    if laws:
        errors = ", ".join(f"{k} {v:.2g}" for k, v in laws["error"].items())
        print(f"Table: {laws['tabulated']} laws, {laws.get('intervals')} intervals, "
              f"tolerance {laws['tolerance']:.2g}; errors (relative, at the midpoints): "
              f"{errors}{'; ' + laws['exact'] if 'exact' in laws else ''}")
    n = min(fast["t"].size - 1, exact["t"].size)
    fast["t"], fast["q"] = fast["t"][1:], fast["q"][1:]  # the start: not an output time
    if n:
        print(f"At {n} common times up to {fast['t'][n - 1]:.3g} s the coordinates differ by "
              f"at most {np.abs(fast['q'][:n] - exact['q'][:n]).max():.2g} (m, rad, Euler "
              "parameters)")

if __name__ == "__main__":
    main()
