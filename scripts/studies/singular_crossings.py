"""The explicit methods through singular configurations, tolerance by tolerance.

    python scripts/studies/singular_crossings.py            # about a minute
    python scripts/studies/singular_crossings.py --rtol 1e-4 1e-6 1e-8 1e-9 1e-10 \
        --cases n-four-bar-40

Four cases of ``hexapod.benchmarks`` pass poses where ``Phi_v`` loses rank: the
N-four-bar of IFToMM A02 with 10 windows over 10 s and with the benchmark's 40 windows over
20 s (every crank flat twice per turn, N singular values collapsing at once), and the
anti-parallelogram through its change points, free (2 s) and driven (1 s). Each runs with
each method (default DOPRI5 and DOP853) at every ``rtol`` (``atol = rtol / 100``), stopped
after ``--cpu-budget`` CPU seconds; the table gives the outcome, the error
against the case's independent reference (relative to its size), the singular poses crossed with
nearly dependent rows left out (see docs/simulate.md), steps, rejected steps and CPU time. Writes
nothing: the table goes to standard output.
"""

from __future__ import annotations

import argparse
import sys
import time
from functools import partial
from pathlib import Path

import hexapod as hx
from hexapod.benchmarks import four_bar_dead_points, n_four_bar
from hexapod.simulation import DEFAULT_METHOD

CASES = {"n-four-bar-10": n_four_bar,
         "n-four-bar-40": partial(n_four_bar, 40, t_end=20.0),
         "anti-parallelogram (free)": four_bar_dead_points,
         "anti-parallelogram (driven)": partial(four_bar_dead_points, driven=True)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rtol", type=float, nargs="+", default=[1e-6, 1e-8, 1e-10])
    parser.add_argument("--methods", nargs="+", default=[DEFAULT_METHOD, "dop853-projection"])
    parser.add_argument("--cases", nargs="+", choices=list(CASES), default=list(CASES))
    parser.add_argument("--cpu-budget", type=float, default=120.0, metavar="S")
    args = parser.parse_args(argv)
    print("atol = rtol / 100; error relative to the motion's size, over the whole run\n")
    print("| case | method | rtol | outcome | error | crossings | steps | rejected | CPU (s) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in args.cases:
        case = CASES[name]()
        model = hx.assemble(case.scene)
        for method in args.methods:
            for rtol in args.rtol:
                start = time.process_time()
                result = hx.simulate(model, case.t_end, method=method, rtol=rtol,
                                     atol=rtol / 100, cpu_budget=args.cpu_budget)
                cpu = time.process_time() - start
                outcome = (result.status if result.success
                           else f"{result.status} at t = {result.t[-1]:.4g} s")
                error = (f"{case.error(model, result.t, result.q):.1e}" if result.success
                         else "-")
                c = result.counters
                print(f"| {name} | {method} | {rtol:.0e} | {outcome} | {error} | {c.crossings} "
                      f"| {c.steps} | {c.rejected} | {cpu:.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/scratch_cache.py
    from scratch_cache import use_scratch_cache

    use_scratch_cache()  # never the user's cache
    raise SystemExit(main())
