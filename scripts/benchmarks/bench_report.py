"""CPU of ``hexapod report hexapod``, stage by stage, against the 5 s target (issue 36).

Protocol
--------
* The stages of ``hexapod report hexapod`` (the built-in walking robot, one stride, 501
  samples, its 7 figures), done in this process as the command does them (``hexapod/cli/
  report.py``), each timed by ``time.process_time``: imports (NumPy, hexapod, the report's
  modules; not matplotlib, which the figures load), assembly (scene and model), inverse dynamics
  (interpreted, the command's default), tables (the model of the motion found, body balance,
  feet paths, every file but the figures: ``report_files(figures=False)``).
* Figures: ``render_figures`` of the report's builders (``figure_builders``) with 1 worker
  process (the command's choice for these 7 sheets) and with ``--workers``, each in a process
  forked from this one before matplotlib is loaded, as the command would draw them; its CPU
  counts the forked process and the processes it forks (``RUSAGE_CHILDREN``), the import of
  matplotlib included. The minimum of ``--repeats``.
* Per figure: after those, here (matplotlib then loaded, its import timed once), each figure
  built and encoded (``png_bytes(build())``), the minimum of ``--repeats`` CPU times.
* The whole command once more as a process (``python -m hexapod report hexapod``), its CPU
  with its children's, beside the sum of the stages.
* Target: the whole command within 5 s of CPU (issue 36); the total is the sum of the stages,
  the figures drawn as the command draws them (one process). Timings are noisy on a shared
  machine: the load average is printed at the start and the end; compare figures of one run.
* An earlier revision: ``git worktree add ../before REV``, then this script with
  ``PYTHONPATH=../before`` (the whole command then runs that revision too); it needs the public
  ``hexapod.output.figure_builders`` and ``render_figures`` (from the revision after ``a20b28a``).

    OPENBLAS_NUM_THREADS=1 python3 scripts/benchmarks/bench_report.py [--repeats 3]
        [--workers 2]           # about 2 min here

Everything is written to a temporary folder, removed at the end.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

from measure import load_average, one_blas_thread, run_process, start

one_blas_thread()  # before NumPy loads

TARGET = 5.0  # s of CPU, the whole command (issue 36)
SCENE, SAMPLES = "hexapod", 501
COMMAND_WORKERS = 1  # the command draws the report's 7 sheets in its own process


def timed(call):
    """``call()`` and the CPU seconds it took (this process)."""
    started = time.process_time()
    value = call()
    return value, time.process_time() - started


def children_cpu() -> float:
    import resource

    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def forked_figures(builders: dict, workers: int) -> tuple[float, float]:
    """CPU (the forked process and its own children) and wall time of drawing ``builders``
    with ``workers`` processes, in a process forked from this one (matplotlib not loaded)."""
    from hexapod.output import render_figures

    before, started = children_cpu(), time.perf_counter()
    pid = os.fork()
    if pid == 0:  # the child draws, as the command would, and leaves without cleaning up
        code = 0
        try:
            render_figures(builders, workers)
        except BaseException:  # noqa: BLE001 - reported through the exit status
            code = 1
        os._exit(code)
    _, status = os.waitpid(pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"drawing the figures with {workers} workers failed")
    return children_cpu() - before, time.perf_counter() - started


def stages() -> tuple[dict[str, float], dict, object]:
    """The command's stages up to its figures; their CPU seconds, the builders, the times."""
    started = time.process_time()
    import numpy as np

    from hexapod import assemble, body_balance, inverse_dynamics, load_scene, marker_trajectories
    from hexapod.output import FOOT_MARKER, RunInfo, report_files
    from hexapod.simulation import motion_model

    cpu = {"imports": time.process_time() - started}
    model, cpu["assembly"] = timed(lambda: assemble(load_scene(SCENE)))
    duration, why = model.time_window(None)
    times = np.linspace(0.0, duration, SAMPLES)
    result, cpu["inverse dynamics"] = timed(lambda: inverse_dynamics(model, times))

    def tables():
        # as the command: a guided scene's laws are the motion found (the guides are not
        # solved again for the balance)
        model_of_run = motion_model(model, result)
        balance = body_balance(model_of_run, times, result.q, result.v, result.v_dot,
                               result.force, result.torque, result.frame)
        feet = marker_trajectories(model_of_run, result.q, FOOT_MARKER)
        run = RunInfo(SCENE, SCENE, 0.0, f"{why}, {duration:g} s")
        report_files(model_of_run, result, balance, run, feet, figures=False)
        return model_of_run, feet

    (model, feet), cpu["tables"] = timed(tables)
    return cpu, builders_of(model, result, feet), times


def builders_of(model, result, feet) -> dict:
    """The report's figure builders (``hexapod.output.figure_builders``)."""
    from hexapod.output import figure_builders

    return figure_builders(model, result, SCENE, feet)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3, help="runs per figure measurement "
                        "(the minimum is shown; default 3)")
    parser.add_argument("--workers", type=int, default=2, help="figure workers to compare "
                        "with the command's one process (default 2: two cores)")
    options = parser.parse_args(argv)
    start("bench_report")
    cpu, builders, _ = stages()
    variants = sorted({1, options.workers})
    drawn = {w: min(forked_figures(builders, w) for _ in range(options.repeats))
             for w in variants}

    from hexapod.output import png_bytes, prepare_drawing

    _, matplotlib_import = timed(prepare_drawing)
    per_figure = {name: min(timed(lambda b=build: png_bytes(b()))[1]
                            for _ in range(options.repeats)) for name, build in builders.items()}
    with tempfile.TemporaryDirectory(prefix="hexapod-bench-report-") as tmp:
        _, command_cpu = run_process([sys.executable, "-m", "hexapod", "report", SCENE,
                                      "--out", str(Path(tmp) / "report")], Path(tmp))

    print(f"hexapod report {SCENE}: {SAMPLES} samples, {len(builders)} figures; "
          f"{load_average()}\n")
    print("| stage | CPU (s) |\n| --- | ---: |")
    for name, seconds in cpu.items():
        print(f"| {name} | {seconds:.2f} |")
    for w in variants:
        print(f"| figures, {w} worker{'s' if w > 1 else ''} (wall {drawn[w][1]:.2f} s) "
              f"| {drawn[w][0]:.2f} |")
    total = sum(cpu.values()) + drawn[COMMAND_WORKERS][0]
    print(f"| **total** (figures in {COMMAND_WORKERS} process, as the command) "
          f"| **{total:.2f}** |")
    print(f"| the command as a process | {command_cpu:.2f} |")
    print(f"\nTarget: at most {TARGET:g} s of CPU for the whole command: "
          f"{'met' if total <= TARGET else 'missed'} ({total:.2f} s summed, "
          f"{command_cpu:.2f} s measured).\n")
    print(f"Per figure, in this process (matplotlib's import first: {matplotlib_import:.2f} s)"
          f", min of {options.repeats}:\n")
    print("| figure | CPU (s) |\n| --- | ---: |")
    for name, seconds in per_figure.items():
        print(f"| {name} | {seconds:.3f} |")
    print(f"| **all {len(per_figure)}** | **{sum(per_figure.values()):.2f}** |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
