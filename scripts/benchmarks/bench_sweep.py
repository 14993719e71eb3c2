"""What Dask costs a design study: parallel efficiency and scheduling overhead per case.

The same study (by default 200 cases of the walking hexapod: stride period x duty factor x
friction coefficient, inverse dynamics over one stride at ``--samples`` samples) is run three
times, its wall time measured each time:

* in a plain loop in this process (``hexapod.sweeps.run_study`` without Dask), the reference;
* on a local Dask cluster of 1 worker process;
* on a local Dask cluster of ``--workers`` worker processes (default 2).

Printed: the three wall times, the parallel efficiency ``T_1 / (N T_N)``, the scheduling
overhead per case ``(T_1 - T_loop) / T_loop``, and whether the three tables are the same bit
for bit. The clusters' start-up is included in their times (it is what a user waits for).

    python3 scripts/benchmarks/bench_sweep.py [--periods 10] [--duties 5] [--frictions 4]
        [--samples 11] [--workers 2]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from measure import one_blas_thread, start

one_blas_thread()  # as the command line, before NumPy loads: small matrices

from hexapod.sweeps import run_study, study_from_document  # noqa: E402


def study(periods: int, duties: int, frictions: int, samples: int):
    return study_from_document({
        "study": {"name": "bench-sweep", "scene": "hexapod"},
        "fixed": {"gait": "tripod", "ground.policy": "friction"},
        "vary": {"period": {"range": [0.4, 0.8], "steps": periods},
                 "duty": {"range": [0.55, 0.75], "steps": duties},
                 "ground.mu": {"range": [0.4, 1.0], "steps": frictions}},
        "job": {"kind": "inverse", "samples": samples,
                "metrics": ["peak_effort", "peak_ground", "friction_ratio", "energy"]},
    }, "bench-sweep.toml")


def progress(label: str):
    def report(state) -> None:
        print(f"\r{label}: {state.done}/{state.total}", end="", file=sys.stderr, flush=True)
    return report


def timed(label: str, spec, out: Path, **where):
    started = time.perf_counter()
    run = run_study(spec, out=out, progress=progress(label), **where)
    wall = time.perf_counter() - started
    print(file=sys.stderr)
    return wall, run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--periods", type=int, default=10)
    parser.add_argument("--duties", type=int, default=5)
    parser.add_argument("--frictions", type=int, default=4)
    parser.add_argument("--samples", type=int, default=11)
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    spec = study(args.periods, args.duties, args.frictions, args.samples)
    cases = len(spec.cases())
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        loop, plain = timed("plain loop", spec, folder / "loop")
        one, single = timed("1 worker", spec, folder / "one", workers=1)
        many, parallel = timed(f"{args.workers} workers", spec, folder / "many",
                               workers=args.workers)
    same = plain.table.csv_text() == single.table.csv_text() == parallel.table.csv_text()
    status = plain.table.data["status"]
    failed, infeasible = int((status == "failed").sum()), int((status == "infeasible").sum())
    print(f"study: {cases} cases ({failed} failed, {infeasible} infeasible: computed, the "
          f"ground unable to hold the robot), walking hexapod, {args.samples} samples per "
          "stride")
    print(f"{'run':<14} {'wall s':>9} {'s per case':>11}")
    for label, wall in (("plain loop", loop), ("1 worker", one),
                        (f"{args.workers} workers", many)):
        print(f"{label:<14} {wall:9.2f} {wall / cases:11.4f}")
    print(f"parallel efficiency T_1 / ({args.workers} T_{args.workers}): "
          f"{one / (args.workers * many):.3f}")
    print(f"scheduling overhead per case (T_1 - T_loop) / T_loop: {(one - loop) / loop:+.3f}")
    print(f"tables equal bit for bit: {same}")


if __name__ == "__main__":
    start("bench_sweep")
    main()
