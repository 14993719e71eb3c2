"""This checkout against an earlier revision of hexapod, side by side in one run: the costs a user
feels, each measured in fresh processes of both (not a test).

    git worktree add ../hexapod-before c598dbe          # the revision to compare with
    OPENBLAS_NUM_THREADS=1 python3 scripts/benchmarks/against_revision.py ../hexapod-before

Measured, CPU time of the child processes (the minimum over ``--runs``; the ratio is this
checkout's over the revision's, so below 1 is faster):

* ``report``: ``hexapod report hexapod`` (the walking robot, 501 samples, its figures), with an
  empty cache and no C compiler (``HEXAPOD_NO_JIT=1``), as a whole command;
* ``tree``: the tree path of the inverse dynamics, CPU per sample over ``--samples`` samples
  after a warm-up run, on the front leg and the 18-joint robot on a fixed trunk, interpreted
  (CasADi's virtual machine) and compiled (the C compiler's flags of each revision); for the
  revision, also its default evaluation (which may be neither);
* ``exact``: the exact path (``method="saddle"``: every sample solved with its own rank
  decision) of the walking robot, per sample over 20 samples after a warm-up.

The revision is run with its own sources first on ``PYTHONPATH``; both share the installed
dependencies. The load average is printed: compare ratios measured in one run.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

HERE = Path(__file__).resolve().parents[2]

#: A child measuring one path; prints ``label seconds_per_sample`` lines. ``NEW`` tells the
#: API apart: this checkout's execution setting, or the revision's ``compile=`` arguments.
PER_SAMPLE = textwrap.dedent("""
    import sys, time
    import numpy as np
    import hexapod as hx
    NEW = hasattr(hx, "executing")
    case, samples = sys.argv[1], int(sys.argv[2])

    def per_sample(model, times, **options):
        compiled = options.pop("compiled", False)
        if NEW:
            with hx.executing(compiled=compiled):
                hx.inverse_dynamics(model, times[:2], **options)  # builds what it needs
                start = time.process_time()
                hx.inverse_dynamics(model, times, **options)
        else:
            if compiled:
                options["compile"] = True
            hx.inverse_dynamics(model, times[:2], **options)
            start = time.process_time()
            hx.inverse_dynamics(model, times, **options)
        return (time.process_time() - start) / times.size

    if case == "exact":
        model = hx.assemble(hx.load_scene("hexapod"))
        times = np.linspace(0.0, 0.5, 501)[100:120]
        print("exact", per_sample(model, times, method="saddle"))
    else:
        scene = {"front-leg": "front-leg", "18-joints": "hexapod-held"}[case]
        model = hx.assemble(hx.load_scene(scene))
        times = np.linspace(0.0, 1.0, samples)
        if NEW:
            print("interpreted", per_sample(model, times))
        else:
            print("interpreted", per_sample(model, times, compile=False, arrays=False))
            print("default", per_sample(model, times))
        print("compiled", per_sample(model, times, compiled=True))
""")


def _environment(source: Path, cache: Path, **extra: str) -> dict:
    env = {k: v for k, v in os.environ.items() if not k.startswith("HEXAPOD_")}
    env.update(PYTHONPATH=str(source), OPENBLAS_NUM_THREADS="1", HEXAPOD_CACHE_DIR=str(cache),
               **extra)
    return env


def _report_cpu(source: Path, runs: int) -> float:
    """The least CPU time of ``hexapod report hexapod`` over ``runs`` whole commands, each with
    an empty cache and no compiler."""
    import resource

    best = float("inf")
    for _ in range(runs):
        with tempfile.TemporaryDirectory() as scratch:
            folder = Path(scratch)
            env = _environment(source, folder / "cache", HEXAPOD_NO_JIT="1")
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            done = subprocess.run([sys.executable, "-m", "hexapod", "report", "hexapod", "--out",
                                   str(folder / "report")], env=env, cwd=folder,
                                  capture_output=True, text=True)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            if done.returncode != 0:
                raise SystemExit(f"report failed with {source}:\n{done.stderr}")
            best = min(best, (after.ru_utime - before.ru_utime)
                       + (after.ru_stime - before.ru_stime))
    return best


def _per_sample(source: Path, case: str, samples: int, runs: int) -> dict[str, float]:
    best: dict[str, float] = {}
    for _ in range(runs):
        with tempfile.TemporaryDirectory() as scratch:
            env = _environment(source, Path(scratch) / "cache")
            done = subprocess.run([sys.executable, "-c", PER_SAMPLE, case, str(samples)],
                                  env=env, cwd=scratch, capture_output=True, text=True)
            if done.returncode != 0:
                raise SystemExit(f"{case} failed with {source}:\n{done.stderr}")
            for line in done.stdout.strip().splitlines():
                label, seconds = line.split()
                best[label] = min(best.get(label, float("inf")), float(seconds))
    return best


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("revision", type=Path, help="a checkout of the revision to compare with")
    parser.add_argument("--runs", type=int, default=3, help="processes per figure (default 3)")
    parser.add_argument("--samples", type=int, default=1000,
                        help="samples of the tree path (default 1000)")
    parser.add_argument("--only", nargs="+", choices=("report", "tree", "exact"),
                        default=["report", "tree", "exact"])
    args = parser.parse_args(argv)
    revision = args.revision.resolve()
    print(f"load average {os.getloadavg()[0]:.2f}; {args.runs} runs each; this checkout / "
          f"{revision.name}")
    if "report" in args.only:
        now, before = _report_cpu(HERE, args.runs), _report_cpu(revision, args.runs)
        print(f"report hexapod (empty cache, no compiler): {now:.2f} s / {before:.2f} s CPU "
              f"= {now / before:.2f}")
    if "exact" in args.only:
        now = _per_sample(HERE, "exact", 20, args.runs)["exact"]
        before = _per_sample(revision, "exact", 20, args.runs)["exact"]
        print(f"exact path, walking robot: {now * 1e3:.1f} ms / {before * 1e3:.1f} ms a sample "
              f"= {now / before:.2f} ({before / now:.1f} times faster)")
    if "tree" in args.only:
        for case in ("front-leg", "18-joints"):
            now = _per_sample(HERE, case, args.samples, args.runs)
            before = _per_sample(revision, case, args.samples, args.runs)
            for label in ("interpreted", "compiled"):
                print(f"tree path, {case}, {label}: {now[label] * 1e6:.1f} us / "
                      f"{before[label] * 1e6:.1f} us a sample = {now[label] / before[label]:.2f}")
            ratio = now["interpreted"] / before["default"]
            print(f"tree path, {case}, the revision's default: {before['default'] * 1e6:.1f} us"
                  f" a sample (this checkout interpreted: {ratio:.2f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
