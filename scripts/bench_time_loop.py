"""The compiled time loop of DOPRI5 and DOP853 against the Python loop, on the one-body pendulum
(data/scenes/pendulum.toml: a 1 m, 1 kg rod about its end, released horizontal).

    python scripts/bench_time_loop.py                  # both parts (about a minute of CPU)
    python scripts/bench_time_loop.py --part step      # CPU per step only
    python scripts/bench_time_loop.py --part iftomm --python   # also the Python loop (slow)

Part ``step``: CPU per step over ``--horizon`` seconds (100 by default) of DOPRI5, DOP853 and
RK4 with Baumgarte's stabilisation (fixed steps of 0.01 s), every loop in one run
(``python``: one step per Python call; ``vm``: the compiled loop evaluated by CasADi's virtual
machine; ``c``: the same compiled to C before the run, its compilation not counted), with the
part of it spent inside the kernel's calls and per right-hand side.

Part ``iftomm``: the IFToMM simple pendulum over 2000 s, DOP853 and DOPRI5 over a ladder of
tolerances (``rtol = atol``) with the default loop (``auto``: the virtual machine, then C once
the run is foreseen to be long, the compiler's CPU counted in the run's): the largest distance of
the centre of mass from the exact solution over every accepted step, the CPU time of the time
loop, the steps, the energy drift. The target: 1e-6 m everywhere within 5 s of CPU.

Writes OUT/time_loop.md (the tables) and OUT/time_loop.csv (one row per run) with --out.
"""

from __future__ import annotations

import argparse
import csv
import io
import sys
from pathlib import Path

import numpy as np

import hexapod as hx
from hexapod.benchmarks import long_pendulum

ROOT = Path(__file__).resolve().parents[1]
#: each method's setting in part ``step``: the adaptive ones' tolerances near 1e-6 m over
#: 2000 s, RK4's step (about 190 per period)
STEP_SETTINGS = {"dopri5-projection": {"rtol": 1e-10, "atol": 1e-10},
                 "dop853-projection": {"rtol": 1e-12, "atol": 1e-12},
                 "rk4-baumgarte": {"step": 0.01}}
#: the ladders of part ``iftomm``
LADDERS = {"dop853-projection": (1e-10, 1e-11, 1e-12, 1e-13),
           "dopri5-projection": (1e-10, 1e-11, 1e-12)}
IFTOMM_SECONDS = 2000.0
TARGET_M, TARGET_CPU = 1e-6, 5.0


def per_step(horizon: float, loops: tuple[str, ...]) -> list[dict]:
    """CPU per step of each method and loop over ``horizon`` seconds of the pendulum."""
    case = long_pendulum(duration=horizon)
    model = hx.assemble(case.scene)
    rows = []
    for method, settings in STEP_SETTINGS.items():
        for loop in loops:
            result = hx.simulate(model, horizon, method=method, every=10**9,
                                 options={"loop": loop}, **settings)
            steps, rhs = result.counters.steps, result.counters.rhs
            inside = result.options["loop"]["cpu_s"]
            rows.append({"part": "step", "method": method, "loop": loop,
                         "setting": " ".join(f"{k} {v:g}" for k, v in settings.items()),
                         "t_end_s": horizon, "status": result.status, "steps": steps,
                         "rhs": rhs, "cpu_s": result.cpu_time,
                         "us_per_step": 1e6 * result.cpu_time / steps,
                         "kernel_us_per_step": 1e6 * inside / steps,
                         "kernel_us_per_rhs": 1e6 * inside / rhs if inside else None,
                         "max_error_m": _error(case, result)})
    return rows


def iftomm(python: bool) -> list[dict]:
    """The 2000 s pendulum over the ladders (and the Python loop at DOP853's 1e-12)."""
    case = long_pendulum(duration=IFTOMM_SECONDS)
    model = hx.assemble(case.scene)
    runs = [(method, tol, "auto") for method, ladder in LADDERS.items() for tol in ladder]
    if python:
        runs.append(("dop853-projection", 1e-12, "python"))
    rows = []
    for method, tol, loop in runs:
        # a fresh model: the kernels built for one run are not reused by the next
        model = hx.assemble(case.scene)
        result = hx.simulate(model, IFTOMM_SECONDS, method=method, rtol=tol, atol=tol,
                             options={"loop": loop})
        rows.append({"part": "iftomm", "method": method, "loop": loop, "rtol": tol,
                     "t_end_s": IFTOMM_SECONDS, "status": result.status,
                     "steps": result.counters.steps, "rhs": result.counters.rhs,
                     "cpu_s": result.cpu_time,
                     "us_per_step": 1e6 * result.cpu_time / result.counters.steps,
                     "kernels": "+".join(result.options["loop"]["kernels"]) or "-",
                     "max_error_m": _error(case, result),
                     "final_error_m": _error(case, result, last=True),
                     "energy_drift": result.energy_drift})
        print(_line(rows[-1]), file=sys.stderr, flush=True)
    return rows


def _error(case, result, last: bool = False) -> float:
    """The largest (or the last) distance of the centre of mass from the exact one (m)."""
    error = np.linalg.norm(result.q[:, :3] - case.reference(result.t), axis=1)
    return float(error[-1] if last else error.max())


def _line(row: dict) -> str:
    return (f"{row['method']} rtol {row['rtol']:g} ({row['loop']}): {row['status']}, "
            f"{row['steps']} steps, {row['cpu_s']:.2f} s CPU, error {row['max_error_m']:.2e} m")


def step_table(rows: list[dict]) -> str:
    lines = ["| method | setting | loop | steps | CPU s | CPU per step (us) | in the kernel "
             "(us per step) | per right-hand side (us) |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        per_rhs = "-" if r["kernel_us_per_rhs"] is None else f"{r['kernel_us_per_rhs']:.2f}"
        lines.append(f"| {r['method']} | {r['setting']} | {r['loop']} | {r['steps']} | "
                     f"{r['cpu_s']:.3f} | {r['us_per_step']:.1f} | "
                     f"{r['kernel_us_per_step']:.1f} | {per_rhs} |")
    return "\n".join(lines)


def iftomm_table(rows: list[dict]) -> str:
    lines = ["| method | rtol = atol | loop (kernels) | steps | CPU s | largest error (m) | "
             "final error (m) | energy drift | 1e-6 m within 5 s |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        met = r["max_error_m"] <= TARGET_M and r["cpu_s"] <= TARGET_CPU
        lines.append(f"| {r['method']} | {r['rtol']:g} | {r['loop']} ({r['kernels']}) | "
                     f"{r['steps']} | {r['cpu_s']:.2f} | {r['max_error_m']:.2e} | "
                     f"{r['final_error_m']:.2e} | {r['energy_drift']:.1e} | "
                     f"{'yes' if met else 'no'} |")
    return "\n".join(lines)


def recommendation(rows: list[dict]) -> str:
    """The cheapest run that meets 1e-6 m, per method."""
    out = []
    for method in LADDERS:
        good = [r for r in rows if r["method"] == method and r["loop"] != "python"
                and r["status"] == "finished" and r["max_error_m"] <= TARGET_M]
        if good:
            best = min(good, key=lambda r: r["cpu_s"])
            out.append(f"{method}: 1e-6 m everywhere at rtol {best['rtol']:g} in "
                       f"{best['cpu_s']:.2f} s of CPU ({best['max_error_m']:.1e} m)")
        else:
            out.append(f"{method}: 1e-6 m not reached on its ladder")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--part", choices=("step", "iftomm", "both"), default="both")
    parser.add_argument("--horizon", type=float, default=100.0,
                        help="seconds of the pendulum in part step (default 100)")
    parser.add_argument("--python", action="store_true",
                        help="also the Python loop over 2000 s at DOP853's 1e-12 (slow)")
    parser.add_argument("--out", help="output directory (time_loop.md, time_loop.csv)")
    args = parser.parse_args(argv)
    rows, text = [], []
    if args.part in ("step", "both"):
        step_rows = per_step(args.horizon, ("python", "vm", "c"))
        rows += step_rows
        text += [f"CPU per step, pendulum over {args.horizon:g} s:", "", step_table(step_rows),
                 ""]
    if args.part in ("iftomm", "both"):
        iftomm_rows = iftomm(args.python)
        rows += iftomm_rows
        text += [f"IFToMM pendulum over {IFTOMM_SECONDS:g} s:", "", iftomm_table(iftomm_rows),
                 "", recommendation(iftomm_rows), ""]
    report = "\n".join(text)
    print(report)
    if args.out:
        columns = list(dict.fromkeys(key for row in rows for key in row))
        table = io.StringIO()
        writer = csv.DictWriter(table, columns, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
        hx.write_directory_atomically(args.out, {"time_loop.md": report.encode(),
                                                 "time_loop.csv": table.getvalue().encode()})
        print(f"wrote {args.out}/: time_loop.md, time_loop.csv")
    return 0


if __name__ == "__main__":
    sys.exit(main())
