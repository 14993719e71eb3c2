"""``hexapod check``: where each integrator breaks, why, and what to use."""

from __future__ import annotations

import sys
from pathlib import Path

from hexapod.cli.common import positive
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
    "diagnostics, the stable steps, every run: finished or failed and why, steps, rejected "
    "steps, CPU time, constraint drift, energy error, error, condition number along the run), "
    "runs.csv, diagnostics.json, stability.csv and the figures outcomes.png, stability.png and "
    "condition.png, written whole or not at all.")


def add_arguments(parser) -> None:
    parser.add_argument("scene", nargs="?", metavar="SCENE",
                        help="a scene file or built-in scene (default: the extreme-case suite)")
    parser.add_argument("--methods", nargs="+", choices=list(METHODS), metavar="NAME",
                        help="integrators to run (default: all)")
    parser.add_argument("--t-end", type=positive(float), metavar="S",
                        help="duration of the runs on SCENE in s (default: one cycle of its "
                        "periodic laws, or 1 s)")
    parser.add_argument("--quick", action="store_true",
                        help="shorter runs and fewer stiffnesses (the suite in about 25 minutes "
                        "on 2 cores, with --budget 20)")
    parser.add_argument("--budget", type=positive(float), default=60.0, metavar="S",
                        help="CPU seconds after which a run is stopped, as failed (default 60)")
    parser.add_argument("--out", metavar="DIR",
                        help="the directory to write (default: extreme-check, or "
                        "SCENE-NAME-check)")


def run(args) -> int:
    from hexapod._support.files import write_directory_atomically
    from hexapod.algorithms.kinematics import consistent_state
    from hexapod.benchmarks.check import build_suite, report_files, run_suite, scene_case
    from hexapod.benchmarks.stable_steps import stability_study, stiff_spring
    from hexapod.model.assemble import assemble
    from hexapod.scene.builtin import builtin_scenes, load_scene
    from hexapod.simulation.diagnostics import diagnose

    def say(line: str) -> None:
        print(f"  {line}", file=sys.stderr, flush=True)

    if args.scene:
        scene = load_scene(args.scene)
        model = assemble(scene)
        duration, _ = model.time_window(args.t_end)
        cases = [scene_case(scene.name, model, duration)]
        stiffnesses = ()
        out = Path(args.out or f"{scene.name}-check")
    else:
        standing = load_scene("hexapod-standing") if "hexapod-standing" in builtin_scenes() \
            else None
        print("building the cases", file=sys.stderr)
        cases = build_suite(quick=args.quick, standing=standing)
        stiffnesses = (1e3, 1e6, 1e9) if args.quick else (1e3, 1e5, 1e7, 1e9)
        out = Path(args.out or "extreme-check")
    diagnoses = {}
    for case in cases:
        say(f"{case.name}: diagnostics at the start")
        data = case.model.create_data()
        q, v = consistent_state(case.model, data)
        diagnoses[case.name] = diagnose(case.model, data, 0.0, q, v)
    runs = run_suite(cases, args.methods, budget=args.budget, progress=say)
    stability = stability_study(stiff_spring, stiffnesses, progress=say) if stiffnesses else []
    say("figures")
    command = "hexapod check" + (f" {args.scene}" if args.scene else "") + (
        " --quick" if args.quick else "")
    files = report_files(cases, runs, diagnoses, stability, command)
    write_directory_atomically(out, files)
    if args.scene:
        print(diagnoses[cases[0].name].text())
    print(files["check.md"].decode().split("## Diagnostics")[0].rstrip())
    print(f"wrote {out}/: {', '.join(files)}")
    return 0
