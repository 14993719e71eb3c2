"""``hexapod bench``: the work-precision study of every integrator."""

from __future__ import annotations

import sys
from pathlib import Path

from hexapod.catalog import PROBLEMS
from hexapod.cli.common import seconds
from hexapod.cli.outputs import output_directory, suffixes
from hexapod.simulation.methods import METHODS

HELP = "work-precision study: error against CPU time of every integrator"
DESCRIPTION = (
    "Run every integrator over a ladder of tolerances (adaptive methods) or steps (fixed-step "
    "ones) on Andrews' squeezing mechanism, the closed-loop pendulum of Richard, Anderson and "
    "Andrews (1989), a pendulum over 100 periods and the front leg falling, each against its "
    "reference, and write OUT: work_precision.md (the CPU time to reach 1e-6 and 1e-9 relative "
    "error in positions, per method and problem; the check of Andrews' forces at joint E against "
    "the published multipliers), runs.csv (every run), work_precision.png (error against CPU "
    "time) and drift_<problem>.png (constraint drift and energy error against time). Run it from "
    "a checkout of the project (it reads data/).")


def add_arguments(parser) -> None:
    parser.add_argument("--problems", nargs="+", choices=PROBLEMS, default=list(PROBLEMS),
                        metavar="NAME", help=f"problems (default all: {', '.join(PROBLEMS)})")
    parser.add_argument("--methods", nargs="+", choices=list(METHODS), metavar="NAME",
                        help="integrators (default: all)")
    parser.add_argument("--quick", action="store_true",
                        help="shorter horizons and ladders (a first look, a few minutes)")
    parser.add_argument("--budget", type=seconds, default=30.0, metavar="S",
                        help="stop a method's ladder after a run costing more CPU than this "
                        "(default 30 s)")
    parser.add_argument("--data", default="data", metavar="DIR",
                        help="the project's data directory (default: data)")
    parser.add_argument("--out", metavar="DIR",
                        help="the directory to write (default: work-precision)")


def run(args) -> int:

    from hexapod._support.files import write_directory_atomically
    from hexapod.benchmarks.work_precision import (
        andrews_check,
        build_problems,
        drift_figure,
        run_study,
        runs_csv_text,
        table,
        units_json_text,
        work_precision_figure,
    )
    from hexapod.errors import InputFileError
    from hexapod.output.figures import png_bytes
    from hexapod.scene.builtin import load_scene
    from hexapod.simulation.registry import INTEGRATORS

    data_dir = Path(args.data)
    if not (data_dir / "scenes").is_dir() or not (data_dir / "benchmarks").is_dir():
        raise InputFileError(f"{data_dir}: not the project's data directory (it needs scenes/ "
                             "and benchmarks/): run from a checkout, or pass --data DIR")
    out = output_directory(args.out, "work-precision", inputs=[data_dir],
                           ours=suffixes(".md", ".csv", ".json", ".png"))
    leg = load_scene("front-leg") if "front-leg" in args.problems else None

    def say(line: str) -> None:
        print(f"  {line}", file=sys.stderr, flush=True)

    print("building the problems and their references", file=sys.stderr)
    problems = build_problems(args.problems, data_dir, args.quick, leg)
    runs = run_study(problems, args.methods, quick=args.quick, budget=args.budget, progress=say)
    text = ["# Work-precision study", "",
            f"Command: `hexapod bench{' --quick' if args.quick else ''} --budget {args.budget:g}`;"
            " CPU time of each run's time loop; relative error in positions (see "
            "docs/work-precision.md).", "", table(runs)]
    if "andrews" in args.problems:
        check, _ = andrews_check(data_dir)
        text += ["## Andrews' mechanism: our reference and the forces at joint E", "", check]
    files = {"work_precision.md": "\n".join(text).encode()}
    files["runs.csv"] = runs_csv_text(runs).encode()
    files["units.json"] = units_json_text().encode()
    files["work_precision.png"] = png_bytes(work_precision_figure(runs, problems))
    for problem in problems:
        settings = {}
        for method in args.methods or INTEGRATORS:
            cls = INTEGRATORS[method]
            settings[method] = ({"rtol": 1e-8, "atol": 1e-8 * problem.scale} if cls.adaptive
                                else {"step": problem.t_end / (4 * problem.steps)})
        say(f"{problem.name}: drift and energy along one run per method")
        files[f"drift_{problem.name}.png"] = png_bytes(drift_figure(problem, settings))
    write_directory_atomically(out, files)
    print(files["work_precision.md"].decode())
    print(f"wrote {out}/: {', '.join(files)}")
    return 0
