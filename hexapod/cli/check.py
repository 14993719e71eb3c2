"""``hexapod check``: where each integrator breaks, why, and what to use."""

from __future__ import annotations

import sys
import time

from hexapod.cli.common import seconds
from hexapod.cli.outputs import given_files, output_directory, suffixes
from hexapod.simulation.methods import METHODS

HELP = "where each integrator breaks, why, and what to use"
DESCRIPTION = (
    "Without SCENE: the extreme-case suite. Every integrator runs on stiff springs (1e3 to 1e9 "
    "N/m) and a stiff flyball governor, extreme mass ratios (1e-6), singular configurations (a "
    "four-bar through its dead points, the N-four-bar through the pose where its DOF jumps, a "
    "stretched leg), redundant constraints (Bricard's mechanism, the hexapod standing on its "
    "feet), a long horizon and very large steps, each against an independent reference where it "
    "has one; the largest stable step of the explicit methods is predicted from the linearised "
    "modes and measured on stiff springs. With SCENE: the diagnostics of SCENE at its start and "
    "every integrator on it. Writes the directory OUT: check.md (what to use per case, the "
    "diagnostics, the stable steps, every run: finished, failed or stopped by the budget and "
    "why, steps, rejected steps, CPU and wall time, constraint drift, energy error, error, "
    "condition number along the run), "
    "runs.csv, diagnostics.json, stability.csv and the figures outcomes.png, stability.png and "
    "condition.png, written whole or not at all.")


def add_arguments(parser) -> None:
    parser.add_argument("scene", nargs="?", metavar="SCENE",
                        help="a scene file or built-in scene (default: the extreme-case suite)")
    parser.add_argument("--methods", nargs="+", choices=list(METHODS), metavar="NAME",
                        help="integrators to run (default: all)")
    parser.add_argument("--t-end", type=seconds, metavar="S",
                        help="duration of the runs on SCENE in s (default: one cycle of its "
                        "periodic laws, or 1 s)")
    parser.add_argument("--quick", action="store_true",
                        help="a smoke test of the suite: shorter horizons and fewer steps, two "
                        "stiffnesses in the stability study, and a budget of 5 CPU seconds per "
                        "run unless --budget is given: about a minute of CPU time, a minute or "
                        "two on 2 cores (the whole suite: about half an hour)")
    parser.add_argument("--budget", type=seconds, metavar="S",
                        help="CPU seconds of a run's time loop after which it is stopped, "
                        "reported as stopped by the budget (default 60, or 5 with --quick)")
    parser.add_argument("--out", metavar="DIR",
                        help="the directory to write (default: extreme-check, or "
                        "SCENE-NAME-check)")


def run(args) -> int:
    from hexapod._support.files import write_directory_atomically
    from hexapod.algorithms.assembly import assemble
    from hexapod.algorithms.kinematics import consistent_state
    from hexapod.benchmarks.check import (
        BUDGET,
        QUICK_BUDGET,
        build_suite,
        report_files,
        run_suite,
        scene_case,
        time_total,
    )
    from hexapod.benchmarks.stable_steps import stability_study, stiff_spring
    from hexapod.scene.builtin import builtin_scenes, load_scene
    from hexapod.simulation.diagnostics import diagnose

    def say(line: str) -> None:
        print(f"  {line}", file=sys.stderr, flush=True)

    started = time.perf_counter(), time.process_time()
    budget = args.budget if args.budget is not None else (
        QUICK_BUDGET if args.quick and not args.scene else BUDGET)

    ours = suffixes(".md", ".csv", ".json", ".png")
    if args.scene:
        scene = load_scene(args.scene)
        out = output_directory(args.out, f"{scene.name}-check", inputs=given_files(args.scene),
                               ours=ours)
        model = assemble(scene)
        duration, _ = model.time_window(args.t_end)
        cases = [scene_case(scene.name, model, duration)]
        stiffnesses = ()
    else:
        out = output_directory(args.out, "extreme-check", ours=ours)
        standing = load_scene("hexapod-standing") if "hexapod-standing" in builtin_scenes() \
            else None
        print("building the cases", file=sys.stderr)
        cases = build_suite(quick=args.quick, standing=standing)
        stiffnesses = (1e3, 1e9) if args.quick else (1e3, 1e5, 1e7, 1e9)
    diagnoses = {}
    for case in cases:
        say(f"{case.name}: diagnostics at the start")
        data = case.model.create_data()
        q, v = consistent_state(case.model, data)
        diagnoses[case.name] = diagnose(case.model, data, 0.0, q, v)
    runs = run_suite(cases, args.methods, budget=budget, progress=say)
    stability = stability_study(stiff_spring, stiffnesses, progress=say) if stiffnesses else []
    say("figures")
    command = "hexapod check" + (f" {args.scene}" if args.scene else "") + (
        " --quick" if args.quick else "") + f" --budget {budget:g}"
    files = report_files(cases, runs, diagnoses, stability, command)
    write_directory_atomically(out, files)
    if args.scene:
        print(diagnoses[cases[0].name].text())
    print(files["check.md"].decode().split("## Diagnostics")[0].rstrip())
    print(f"wrote {out}/: {', '.join(files)}")
    print(f"{time_total(runs)}; the whole check: {time.perf_counter() - started[0]:.0f} s wall, "
          f"{time.process_time() - started[1]:.0f} s CPU")
    return 0
