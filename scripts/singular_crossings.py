"""The default method through singular configurations, tolerance by tolerance.

    python scripts/singular_crossings.py            # about half a minute
    python scripts/singular_crossings.py --rtol 1e-6 1e-8 1e-10 1e-11

Three cases of ``hexapod.benchmarks`` pass poses where ``Phi_v`` loses rank: the
N-four-bar of IFToMM A02 (10 windows, 10 s; every crank flat twice per turn), and the
anti-parallelogram through its change points, free (2 s) and driven (1 s). Each runs with the
default method at every ``rtol`` (``atol = rtol / 100``); the table gives the outcome, the error
against the case's independent reference (relative to its size), the singular poses crossed with
nearly dependent rows left out (see docs/simulate.md), steps, rejected steps and CPU time. Writes
nothing: the table goes to standard output.
"""

from __future__ import annotations

import argparse
import time
from functools import partial

import hexapod as hx
from hexapod import DEFAULT_METHOD
from hexapod.benchmarks import four_bar_dead_points, n_four_bar

CASES = {"n-four-bar-10": n_four_bar,
         "anti-parallelogram (free)": four_bar_dead_points,
         "anti-parallelogram (driven)": partial(four_bar_dead_points, driven=True)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rtol", type=float, nargs="+", default=[1e-6, 1e-8, 1e-10])
    args = parser.parse_args(argv)
    print(f"{DEFAULT_METHOD}, atol = rtol / 100\n")
    print("| case | rtol | outcome | error | crossings | steps | rejected | CPU (s) |")
    print("|---|---|---|---|---|---|---|---|")
    for name, build in CASES.items():
        case = build()
        model = hx.assemble(case.scene)
        for rtol in args.rtol:
            start = time.process_time()
            result = hx.simulate(model, case.t_end, rtol=rtol, atol=rtol / 100)
            cpu = time.process_time() - start
            error = case.error(model, result.t, result.q)
            outcome = (result.status if result.success
                       else f"{result.status} at t = {result.t[-1]:.4g} s")
            c = result.counters
            print(f"| {name} | {rtol:.0e} | {outcome} | {error:.1e} | {c.crossings} | {c.steps} | "
                  f"{c.rejected} | {cpu:.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
