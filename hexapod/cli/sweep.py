"""``hexapod sweep``: a design study, many cases, on Dask or in this process."""

from __future__ import annotations

import sys

from hexapod.cli.common import MAX_WORKERS, at_least
from hexapod.cli.outputs import given_files, output_directory

HELP = "a design study: many gaits, robots or settings, one table and its figures"
DESCRIPTION = (
    "Run the study SPEC.toml (docs/sweeps.md): a base scene, the parameters held and varied "
    "(arguments of the built-in scene's builder such as period, speed, duty, scale, payload, "
    "segment lengths, or scene keys such as ground.mu and ground.policy; lists, grids or seeded "
    "random draws), and the job per case (inverse dynamics over a stride, or a simulation). "
    "Writes in OUT: study.csv (one row per case, one column per parameter and metric: peak "
    "and RMS efforts, peak joint forces and moments, peak ground forces and friction ratios "
    "per foot, energy per stride, cost of transport, status), columns.csv (each column's "
    "unit), study.npz, timings.csv (each case's cost) and figures/ (each metric against each "
    "parameter; a heat map for two). Cases run as tasks of dask.distributed: on a local "
    "cluster of worker processes (default, one per core), on --workers N, or on the cluster "
    "of --scheduler; --in-process runs them here without Dask. A failing case is a row with "
    "its message. Each finished case is kept in OUT/cases, so --resume after an interruption "
    "computes only the rest. The study is written beside OUT and swapped in when complete: "
    "an earlier study there stays whole until then (an interrupted or failed run only adds "
    "the cases it finished to its cases/), and OUT holding anything a study did not write "
    "is refused.")


def add_arguments(parser) -> None:
    parser.add_argument("spec", metavar="SPEC.toml", help="the study file")
    parser.add_argument("--out", metavar="DIR",
                        help="the output folder (default: the study's name + '-sweep'); an "
                        "earlier study there is replaced when the new one is complete, unless "
                        "--resume; a folder holding anything else is refused")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--workers", type=at_least(1, MAX_WORKERS), metavar="N",
                       help="worker processes of the local Dask cluster (default: one per "
                       "core)")
    where.add_argument("--scheduler", metavar="ADDRESS", type=_address,
                       help="send the cases to this running Dask scheduler, "
                       "tcp://HOST:PORT (e.g. tcp://10.0.0.5:8786)")
    where.add_argument("--in-process", action="store_true",
                       help="run the cases one after the other in this process, without Dask")
    parser.add_argument("--resume", action="store_true",
                        help="keep the cases already finished in DIR (same parameters, scene, "
                        "job and code version) and compute the rest")
    parser.add_argument("--scheduler-timeout", type=_seconds, metavar="SECONDS",
                        help="seconds the --scheduler has to answer and to have a worker, "
                        "after which the study ends with an error (default: "
                        "HEXAPOD_SCHEDULER_TIMEOUT, else 10)")
    parser.add_argument("--max-cases", type=at_least(1), metavar="N",
                        help="the most cases the study may have, checked before any work "
                        "(default: HEXAPOD_MAX_CASES, else 100000)")


def _address(text: str) -> str:
    import argparse

    from hexapod.sweeps.cluster import scheduler_address

    try:
        return scheduler_address(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def _seconds(text: str) -> float:
    import argparse

    from hexapod.errors import HexapodError
    from hexapod.sweeps.cluster import scheduler_timeout

    try:
        return scheduler_timeout(float(text))
    except (ValueError, HexapodError) as error:
        raise argparse.ArgumentTypeError(str(error).replace("scheduler timeout: ", "")) \
            from None


def run(args) -> int:
    import os
    import time

    from hexapod.sweeps.run import run_study
    from hexapod.sweeps.spec import read_study

    study = read_study(args.spec, args.max_cases)
    # the study's own reader of the folder checks its contents (cases/, figures/, --resume)
    out = output_directory(args.out, f"{_safe(study.name)}-sweep",
                           inputs=given_files(args.spec, study.scene))
    workers = args.workers
    if not args.in_process and args.scheduler is None and workers is None:
        workers = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") \
            else (os.cpu_count() or 1)
    if args.in_process:
        workers = None
    elif args.scheduler is None:
        _require_dask()
    started = time.perf_counter()
    run = run_study(study, workers=workers, scheduler=args.scheduler, out=out,
                    resume=args.resume, progress=_progress(),
                    announce=lambda text: print(text, file=sys.stderr),
                    max_cases=args.max_cases, scheduler_timeout=args.scheduler_timeout)
    print(file=sys.stderr)
    status = run.table.data["status"]
    failed = int(((status != "ok") & (status != "infeasible")).sum())
    infeasible = int((status == "infeasible").sum())
    print(f"study '{study.name}': {len(run.table)} cases ({run.computed} computed, "
          f"{run.reused} reused, {failed} failed"
          + (f", {infeasible} infeasible: the ground cannot give their feet's forces"
             if infeasible else "") + f") in {time.perf_counter() - started:.1f} s")
    headline = _headline(run.table)
    if headline:
        print(headline)
    print(f"wrote {run.out}/study.csv, columns.csv, study.npz, timings.csv, units.json and "
          "figures/")
    return 0


def _require_dask() -> None:
    import importlib.util

    if importlib.util.find_spec("distributed") is None:
        from hexapod.errors import HexapodError

        raise HexapodError("running a study on Dask needs dask.distributed, which is not "
                           "installed: pip install 'hexapod[sweep]', or run the study in this "
                           "process with --in-process")


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "-" for c in name) or "study"


def _progress():
    import time

    last = [0.0]

    def report(state) -> None:
        now = time.perf_counter()
        if now - last[0] < 0.2 and state.done < state.total:
            return
        last[0] = now
        eta = state.eta()
        left = "" if eta is None else f", about {eta:.0f} s left"
        print(f"\rcases: {state.done}/{state.total} done, {state.failed} failed, "
              + (f"{state.infeasible} infeasible, " if state.infeasible else "") +
              f"{state.running} running{left}   ", end="", file=sys.stderr, flush=True)
    return report


def _headline(table) -> str:
    """The largest peak effort over the study's ok cases (an infeasible case's efforts are not
    ones to size motors by): which joint, in which case."""
    import numpy as np

    efforts = {c: v for c, v in table.metrics().items() if c.startswith("peak_effort:")}
    if not efforts:
        return ""
    names = list(efforts)
    values = np.array([efforts[c] for c in names])  # (joints, cases)
    values = np.where(table.data["status"] == "ok", values, np.nan)
    if not np.isfinite(values).any():
        return ""
    joint, case = np.unravel_index(np.nanargmax(values), values.shape)
    params = ", ".join(f"{name}={_shown(table.data[name][case])}"
                       for name in table.parameters())
    unit = table.units[names[joint]]
    return (f"largest peak effort of the ok cases {values[joint, case]:.4g} {unit} at "
            f"{names[joint].partition(':')[2]}, case {table.data['case'][case]}"
            + (f" ({params})" if params else ""))


def _shown(value) -> str:
    return f"{value:.4g}" if isinstance(value, float) else str(value)
