"""What the benchmarks of this folder share: the start of a benchmark (the scratch cache, the
machine and its load), CPU and wall times, whole processes timed, growth exponents and ratios.

Not a script itself. Timings on a shared machine are noisy: :func:`start` says the load
average when a benchmark starts and when it ends (on stderr), so that a reader can tell a
quiet run from a disturbed one; the CPU times (``time.process_time``, ``os.times``) are the
steadier figures.
"""

from __future__ import annotations

import atexit
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: the scripts' helpers
from scratch_cache import use_scratch_cache  # noqa: E402

#: The variables that set the threads of the BLAS libraries NumPy may load.
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def one_blas_thread() -> None:
    """One BLAS thread (unless the caller set one), as the command line has: the matrices are
    small, and on a shared machine idle BLAS threads spin (a 110 x 110 solve measured 30 ms
    instead of 0.3 ms); ``process_time`` counts every thread. Call it before NumPy loads."""
    for variable in BLAS_THREADS:
        os.environ.setdefault(variable, "1")


def log(message: str) -> None:
    """A progress line on stderr (the results go to stdout)."""
    print(message, file=sys.stderr, flush=True)


def mujoco_warnings_to_stderr(mujoco) -> None:
    """MuJoCo's warnings on stderr: its default handler also appends them to MUJOCO_LOG.TXT
    in the working directory, and a benchmark writes nothing."""
    mujoco.set_mju_user_warning(lambda text: log(f"MuJoCo warning: {text}"))


def load_average() -> str:
    """The machine's load average over 1, 5 and 15 minutes, with its number of cores."""
    try:
        loads = " ".join(f"{x:.2f}" for x in os.getloadavg())
    except (AttributeError, OSError):  # not a POSIX system
        loads = "unknown"
    return f"load average {loads} (1, 5, 15 min) on {os.cpu_count()} cores"


def machine() -> dict:
    """Where a benchmark runs: Python, the platform, the processor and the load."""
    return {"python": sys.version.split()[0], "machine": platform.platform(),
            "processor": platform.processor(), "cores": os.cpu_count(),
            "load": load_average()}


def start(name: str) -> None:
    """Start benchmark ``name``: hexapod's cache in a scratch folder of its own (never the
    user's), and the load average said now and at the end (on stderr)."""
    use_scratch_cache()
    log(f"{name}: Python {sys.version.split()[0]}, {load_average()}")
    atexit.register(lambda: log(f"{name}: ended, {load_average()}"))


def cpu_seconds() -> float:
    """CPU seconds (user and system) of this process and of the child processes it has waited
    for (a compiler, a command timed whole)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def median_time(call: Callable[[int], object], repeats: int,
                clock: Callable[[], float] = time.process_time) -> float:
    """The median time (s) of ``call(k)`` for ``k`` in ``range(repeats)``, by ``clock``: CPU
    time by default (the steadier figure on a shared machine), ``time.perf_counter`` for wall
    time. ``k`` lets a call differ from the one before (e.g. times moved by a picosecond, so
    that no law reuses values it kept)."""
    costs = []
    for k in range(repeats):
        tic = clock()
        call(k)
        costs.append(clock() - tic)
    return statistics.median(costs)


def run_process(command: Sequence[str], cwd: Path, env: dict | None = None
                ) -> tuple[float, float]:
    """The wall time of one process, launch to exit, and its CPU time (s); a failure ends the
    benchmark with the process's stderr."""
    cpu, started = cpu_seconds(), time.perf_counter()
    done = subprocess.run(list(command), cwd=cwd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - started
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed ({done.returncode}):\n{done.stderr}")
    return wall, cpu_seconds() - cpu


def growth_exponent(sizes: Sequence[float], costs: Sequence[float]) -> float:
    """The least-squares slope of log(cost) against log(size)."""
    import numpy as np

    return float(np.polyfit(np.log(sizes), np.log(costs), 1)[0])


def local_slopes(sizes: Sequence[float], costs: Sequence[float]
                 ) -> list[tuple[float, float, float]]:
    """The slopes of log(cost) against log(size) between consecutive sizes:
    ``(size, next size, slope)``."""
    import math

    return [(a, b, math.log(cb / ca) / math.log(b / a))
            for (a, ca), (b, cb) in zip(zip(sizes[:-1], costs[:-1], strict=True),
                                        zip(sizes[1:], costs[1:], strict=True), strict=True)]


def ratio_range(ratios: Sequence[float]) -> str:
    """``min to max`` of some ratios of times, two decimals."""
    return f"{min(ratios):.2f} to {max(ratios):.2f}"
