"""Start-up time of the ``hexapod`` command, as whole processes.

Protocol
--------
* Each command runs ``--runs`` times (default 7) as a fresh process, ``sys.executable -m hexapod
  ...``, from a temporary folder (the only place anything is written: ``report --out`` goes
  there, and the folder is removed at the end); the wall time of each process is measured from
  launch to exit, and the table gives the minimum and the median.
* The baseline is a bare ``python3 -c "import argparse"``: what any Python command line pays.
* Target: ``hexapod --help`` (and ``simulate --help``, ``--version``) within
  max(0.3 s, 2 x the baseline), compared on the minima (the least disturbed runs). ``info`` and
  ``report`` load NumPy and CasADi and build a model: they are shown, not checked.

    python3 scripts/benchmarks/bench_startup.py [--runs 7]

Exit status 1 when a target is missed.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

from measure import run_process, start

#: (label, arguments after ``python3``, checked against the target)
COMMANDS = [
    ("python3 -c 'import argparse'", ["-c", "import argparse"], False),
    ("hexapod --help", ["-m", "hexapod", "--help"], True),
    ("hexapod simulate --help", ["-m", "hexapod", "simulate", "--help"], True),
    ("hexapod --version", ["-m", "hexapod", "--version"], True),
    ("hexapod info", ["-m", "hexapod", "info"], False),
    ("hexapod report --out TMP", ["-m", "hexapod", "report", "--out", "{tmp}/report"], False),
]
FLOOR = 0.3  # s
FACTOR = 2.0


def wall_times(args: list[str], runs: int, cwd: Path) -> list[float]:
    """The wall time of ``runs`` processes ``sys.executable ARGS``; a failure is an error."""
    return [run_process([sys.executable, *args], cwd)[0] for _ in range(runs)]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=7, help="processes per command (default 7)")
    options = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="hexapod-startup-") as tmp:
        results = {}
        for label, args, _ in COMMANDS:
            args = [a.format(tmp=tmp) for a in args]
            results[label] = wall_times(args, options.runs, Path(tmp))
    baseline = min(results[COMMANDS[0][0]])
    target = max(FLOOR, FACTOR * baseline)
    print(f"{options.runs} runs each, {sys.executable} (Python {sys.version.split()[0]})\n")
    print(f"| {'command':<28} | {'min (s)':>8} | {'median (s)':>10} | target |")
    print(f"| {'-' * 28} | {'-' * 7}: | {'-' * 9}: | ------ |")
    missed = []
    for label, _, checked in COMMANDS:
        fastest, median = min(results[label]), statistics.median(results[label])
        verdict = "-"
        if checked:
            verdict = "met" if fastest <= target else "MISSED"
            if fastest > target:
                missed.append(label)
        print(f"| {label:<28} | {fastest:8.3f} | {median:10.3f} | {verdict:<6} |")
    print(f"\ntarget: at most max({FLOOR} s, {FACTOR:g} x {baseline:.3f} s) = {target:.3f} s "
          "(minimum of the runs)")
    if missed:
        print(f"missed: {', '.join(missed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    start("bench_startup")
    sys.exit(main())
