"""The ``hexapod`` command.

Every error a user can cause ends with one message on stderr and a non-zero exit, never a
traceback (set ``HEXAPOD_DEBUG=1`` to see one for an internal error). Each subcommand imports
what it needs when it runs, so that a short job does not pay for the others' imports.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import warnings
from pathlib import Path

import numpy as np

from hexapod.errors import HexapodError, InputFileError
from hexapod.model.assemble import assemble
from hexapod.scene.builtin import DEFAULT_SCENE, builtin_scenes, load_scene
from hexapod.scene.motion import MotionWarning

# ------------------------------------------------------------------ commands

def _jsonable(value):
    """Plain JSON: non-finite numbers (e.g. the smallest singular value of a scene without
    constraints, infinite) written as null."""
    if isinstance(value, dict):
        return {k: _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def _emit(report: dict, as_json: bool, formatter) -> None:
    if as_json:
        json.dump(_jsonable(report), sys.stdout, indent=2, allow_nan=False)
        print()
    else:
        print(formatter(report))


def cmd_dynamics(args) -> int:
    from hexapod.output.describe import describe_state, format_state

    model = assemble(load_scene(args.scene))
    _emit(describe_state(model, args.t), args.json, format_state)
    return 0


def cmd_info(args) -> int:
    from hexapod.output.describe import describe_model, format_model

    model = assemble(load_scene(args.scene))
    _emit(describe_model(model, args.t, graph=args.graph), args.json, format_model)
    return 0


def cmd_inverse(args) -> int:
    from hexapod._support.files import write_atomically
    from hexapod.algorithms.inverse import inverse_dynamics
    from hexapod.output.report import inverse_csv_text
    from hexapod.scene.motion import apply_motion, read_motion

    motion = read_motion(args.motion)
    model = assemble(apply_motion(load_scene(args.model), motion))
    times = motion.times
    progress = _progress("inverse dynamics") if sys.stderr.isatty() else None
    result = inverse_dynamics(model, times, method=args.method, frame=args.frame,
                              progress=progress)
    write_atomically(args.out, inverse_csv_text(model, result))
    if progress is not None:
        print(file=sys.stderr)
    print(f"wrote {args.out}: {times.size} samples, {len(model.joints)} joints "
          f"({result.method} path)")
    return 0


def cmd_report(args) -> int:
    import time

    from hexapod._support.files import write_directory_atomically
    from hexapod.algorithms.balance import body_balance
    from hexapod.algorithms.inverse import inverse_dynamics
    from hexapod.algorithms.kinematics import marker_trajectories
    from hexapod.output.report import FOOT_MARKER, RunInfo, report_files

    scene = load_scene(args.scene)
    model = assemble(scene)
    duration, why = model.time_window(args.duration)
    times = args.start + np.linspace(0.0, duration, args.samples)
    out = Path(args.out or f"{scene.name}-report")
    show = sys.stderr.isatty()
    progress = _progress("inverse dynamics") if show else None
    started = time.perf_counter()
    result = inverse_dynamics(model, times, method=args.method, frame=args.frame,
                              progress=progress)
    run_time = time.perf_counter() - started
    if show:
        print("\rdrawing the figures" + " " * 40, end="", file=sys.stderr, flush=True)
    balance = body_balance(model, times, result.q, result.v, result.v_dot, result.force,
                           result.torque, result.frame)
    feet = marker_trajectories(model, result.q, FOOT_MARKER)
    run = RunInfo(scene.name, args.scene, run_time, f"{why}, {duration:g} s")
    files = report_files(model, result, balance, run, feet)
    write_directory_atomically(out, files)
    if show:
        print("\r" + " " * 60 + "\r", end="", file=sys.stderr)
    worst = int(np.argmax(np.linalg.norm(result.force, axis=2).max(axis=0)))
    print(f"wrote {out}/: {', '.join(files)}")
    print(f"{times.size} samples over {duration:g} s ({result.method} path, {run_time:.3g} s); "
          f"largest joint force {np.linalg.norm(result.force[:, worst], axis=1).max():.4g} N "
          f"at {model.joints[worst].name}; body balance within "
          f"{balance.relative().max():.1e} (relative)")
    return 0


def cmd_simulate(args) -> int:
    from hexapod._support.files import write_directory_atomically
    from hexapod.simulation.loop import simulate
    from hexapod.simulation.results import scene_reference

    scene = load_scene(args.scene)
    model = assemble(scene)
    duration, why = model.time_window(args.t_end)
    out = Path(args.out or f"{scene.name}-simulation")
    show = sys.stderr.isatty()
    result = simulate(model, args.start + duration, t0=args.start, method=args.method,
                      rtol=args.rtol, atol=args.atol, step=args.step, every=args.every,
                      forces=True if args.forces else None,
                      progress=_time_progress(args.method, args.start) if show else None)
    result.source = scene_reference(args.scene)  # for 'hexapod export'
    if show:
        print("\r" + " " * 90 + "\r", end="", file=sys.stderr)
    stats = result.statistics()
    files = {"results.csv": result.csv_text().encode(), "results.npz": result.npz_bytes(),
             "stats.json": (json.dumps(_jsonable(stats), indent=2) + "\n").encode()}
    write_directory_atomically(out, files)
    print(f"wrote {out}/: {', '.join(files)}")
    drift = ("" if result.energy_drift is None
             else f", energy drift {result.energy_drift:.2e} (relative)")
    crossed = (f"{stats['crossings']} singular poses crossed, " if stats.get("crossings")
               else "")
    print(f"{result.method} over {duration:g} s ({why}): {stats['steps']} steps, "
          f"{stats['rejected']} rejected, {crossed}{stats['rhs']} right-hand sides, "
          f"{result.wall_time:.3g} s; max |phi| {result.max_position_violation:.2e}, "
          f"max |Phi_v v - nu| {result.max_velocity_violation:.2e}/s{drift}")
    if not result.success:
        print(f"hexapod: error: {result.message} (the states up to it are in {out}/)",
              file=sys.stderr)
        return 1
    return 0


def cmd_bench(args) -> int:
    import csv
    import io

    from hexapod._support.files import write_directory_atomically
    from hexapod.benchmarks.work_precision import (
        andrews_check,
        build_problems,
        drift_figure,
        run_study,
        table,
        work_precision_figure,
    )
    from hexapod.output.figures import png_bytes
    from hexapod.simulation.registry import INTEGRATORS

    data_dir = Path(args.data)
    if not (data_dir / "scenes").is_dir() or not (data_dir / "benchmarks").is_dir():
        raise InputFileError(f"{data_dir}: not the project's data directory (it needs scenes/ "
                             "and benchmarks/): run from a checkout, or pass --data DIR")
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
    buffer = io.StringIO()
    fields = list(runs[0].as_dict()) if runs else ["problem"]
    writer = csv.DictWriter(buffer, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    writer.writerows(r.as_dict() for r in runs)
    files["runs.csv"] = buffer.getvalue().encode()
    files["work_precision.png"] = png_bytes(work_precision_figure(runs, problems))
    for problem in problems:
        settings = {}
        for method in args.methods or INTEGRATORS:
            cls = INTEGRATORS[method]
            settings[method] = ({"rtol": 1e-8, "atol": 1e-8 * problem.scale} if cls.adaptive
                                else {"step": problem.t_end / (4 * problem.steps)})
        say(f"{problem.name}: drift and energy along one run per method")
        files[f"drift_{problem.name}.png"] = png_bytes(drift_figure(problem, settings))
    out = Path(args.out)
    write_directory_atomically(out, files)
    print(files["work_precision.md"].decode())
    print(f"wrote {out}/: {', '.join(files)}")
    return 0


def cmd_check(args) -> int:
    from hexapod._support.files import write_directory_atomically
    from hexapod.algorithms.kinematics import consistent_state
    from hexapod.benchmarks.extreme import (
        build_suite,
        report_files,
        run_suite,
        scene_case,
        stability_study,
        stiff_spring,
    )
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


def _count(n: int, noun: str) -> str:
    plural = "bodies" if noun == "body" else noun + "s"
    return f"{n} {noun if n == 1 else plural}"


def cmd_export(args) -> int:
    from hexapod._support.files import write_directory_atomically
    from hexapod.output.vtk import frames, read_mesh, read_recording, scene_meshes, vtk_files

    recording = read_recording(args.results)
    source = args.scene or recording.scene
    if not source:
        raise InputFileError(f"{recording.scene_file}: does not say which scene the results "
                             "were computed on; give it with --scene SCENE")
    try:
        scene = load_scene(source)
    except InputFileError as error:
        said = "given with --scene" if args.scene else f"named in {recording.scene_file}"
        hint = "" if args.scene else "; give it with --scene SCENE if it has moved"
        raise InputFileError(f"{error} (the scene {said}{hint})") from None
    meshes = scene_meshes(scene)
    for item in args.mesh or []:
        body, sep, path = item.partition("=")
        if not sep or not body or not path:
            raise InputFileError(f"--mesh {item}: expected BODY=FILE")
        meshes[body] = read_mesh(path)
    model = assemble(scene)
    files = vtk_files(model, frames(model, recording), meshes, every=args.every)
    out = Path(args.vtk)
    write_directory_atomically(out, files)
    count = sum(name.startswith("bodies_") for name in files)
    indices = [name for name in files if name.endswith(".pvd")]
    print(f"wrote {out}/: {count} instants of {recording.kind} '{scene.name}' over t = "
          f"{recording.t[0]:g} ... {recording.t[-1]:g} s, {len(files)} files; open "
          f"{' and '.join(indices)} in ParaView")
    return 0


def _time_progress(method: str, t0: float):
    """A progress bar on stderr, redrawn at most ten times a second."""
    import time

    last = [0.0]

    def report(t: float, t_end: float) -> None:
        now = time.perf_counter()
        if now - last[0] > 0.1 or t >= t_end:
            last[0] = now
            done = min(max((t - t0) / (t_end - t0), 0.0), 1.0)
            bar = "#" * int(30 * done) + "." * (30 - int(30 * done))
            print(f"\r{method} [{bar}] {100 * done:3.0f} %  t = {t:.4g} s", end="",
                  file=sys.stderr, flush=True)
    return report


def _progress(label: str):
    def report(done: int, total: int) -> None:
        if done == total or done % max(1, total // 100) == 0:
            print(f"\r{label}: {done}/{total} samples", end="", file=sys.stderr, flush=True)
    return report


def cmd_validate(args) -> int:
    scene = load_scene(args.scene)
    scene.validate()
    counts = ", ".join(_count(len(items), noun) for items, noun in (
        (scene.bodies, "body"), (scene.joints, "joint"), (scene.drivers, "driver"),
        (scene.forces, "force element")))
    print(f"{args.scene}: scene '{scene.name}' is valid ({counts})")
    return 0


def cmd_scenes(args) -> int:
    if args.name:
        from hexapod.scene.writer import write_scene

        scene = load_scene(args.name)
        if not args.write:
            raise InputFileError("give --write PATH to write the scene to a file")
        write_scene(scene, args.write, header=f"Built-in scene '{args.name}', written by "
                    f"'hexapod scenes {args.name} --write'.")
        print(f"wrote {args.write}")
        return 0
    scenes = builtin_scenes()
    if not scenes:
        print("no built-in scenes installed")
    for name in sorted(scenes):
        marker = " (default)" if name == DEFAULT_SCENE else ""
        print(f"{name}{marker}: {scenes[name].value}")
    return 0


# ------------------------------------------------------------------ main

def _positive(kind):
    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        if not (np.isfinite(value) and value > 0):
            raise argparse.ArgumentTypeError(f"must be positive, got {text}")
        return value
    return parse


def _at_least(smallest: int):
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
        if value < smallest:
            raise argparse.ArgumentTypeError(f"must be at least {smallest}, got {value}")
        return value
    return parse


def _scene_positional(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", nargs="?", default=DEFAULT_SCENE,
                        help="a TOML scene file or a built-in scene name (default: "
                        f"{DEFAULT_SCENE})")


def _scene_arguments(parser: argparse.ArgumentParser, json_help: str) -> None:
    _scene_positional(parser)
    parser.add_argument("--t", type=float, default=0.0, help="time in s (default 0)")
    parser.add_argument("--json", action="store_true", help=json_help)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="hexapod",
        description="Constrained multibody dynamics in absolute coordinates for legged robots.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    p = sub.add_parser(
        "dynamics", help="forward dynamics at one instant: accelerations, multipliers, "
        "joint wrenches and driver efforts",
        description="Assemble SCENE at time T (positions by Newton's method, velocities "
        "projected), solve the saddle-point system and print the joint wrenches (exerted by "
        "the parent on the child, about the joint origin, in the child's joint frame), the "
        "driver efforts, degrees of freedom, redundant rows and the condition number.")
    _scene_arguments(p, "print the results as JSON")
    p.set_defaults(run=cmd_dynamics)

    p = sub.add_parser(
        "info", help="what a scene holds and how it was built: rows, topology, degrees of "
        "freedom, redundancy, condition number",
        description="Describe SCENE: its bodies, joints, drivers and force elements; what the "
        "model was built with (coordinates per body, rows per joint and driver, force terms); "
        "its loops; degrees of freedom counted (Grubler-Kutzbach) and numerical (n_v - rank "
        "Phi_v); the redundant rows and the condition number at the pose assembled at time T.")
    _scene_arguments(p, "print the description as JSON")
    p.add_argument("--graph", action="store_true",
                   help="add the vector-network graph of Richard, Anderson and Andrews: its "
                   "edges and its incidence, cutset and circuit matrices")
    p.set_defaults(run=cmd_info)

    p = sub.add_parser(
        "inverse", help="joint efforts and wrenches of a prescribed motion, as CSV",
        description="Inverse dynamics: drive MODEL (a URDF, a scene file or a built-in scene) "
        "by MOTION.csv (columns t, one per joint in rad or m, optional qd:<joint> and "
        "qdd:<joint>) and write OUT.csv: t, then for every joint tau:<joint> (revolute and "
        "prismatic) and Fx, Fy, Fz, Tx, Ty, Tz:<joint>, the wrench by the parent on the "
        "child about the joint origin in the child's joint frame (N, N m). The file is "
        "written whole or not at all.")
    p.add_argument("model", help="a URDF (.urdf), a TOML scene file or a built-in scene")
    p.add_argument("--motion", required=True, metavar="MOTION.csv", help="the motion")
    p.add_argument("--out", required=True, metavar="OUT.csv", help="the CSV to write")
    p.add_argument("--frame", choices=("joint", "world"), default="joint",
                   help="axes of the wrench components (default: the child's joint frame)")
    p.add_argument("--method", choices=("auto", "tree", "saddle"), default="auto",
                   help="tree-ordered solve (open trees with every joint driven) or the "
                   "saddle-point solve per sample (any mechanism); default: the fastest that "
                   "applies")
    p.set_defaults(run=cmd_inverse)

    p = sub.add_parser(
        "report", help="the liaison force report of a driven scene: CSV, summary, figures",
        description="Inverse dynamics of SCENE (a scene file or a built-in scene whose drivers "
        "prescribe every degree of freedom) over a time window, written to the directory OUT: "
        "inverse.csv (the CSV of 'hexapod inverse'), summary.md (per joint the peak and RMS "
        "force and moment magnitudes, per driver the peak effort and RMS power, per body the "
        "residual of its equations of motion under the reported wrenches) and the figures "
        "forces.png, torques.png, efforts.png and, when bodies have a 'foot' marker, foot.png. "
        "The directory is written whole or not at all.")
    _scene_positional(p)
    p.add_argument("--out", metavar="DIR",
                   help="the directory to write (default: SCENE-NAME-report); an earlier "
                   "report there is replaced")
    p.add_argument("--start", type=float, default=0.0, help="first time in s (default 0)")
    p.add_argument("--duration", type=_positive(float), metavar="S",
                   help="length of the window in s (default: one cycle of the scene's periodic "
                   "laws, e.g. the gait's stride, or 1 s)")
    p.add_argument("--samples", type=_at_least(2), default=501,
                   help="samples over the window, ends included (default 501)")
    p.add_argument("--frame", choices=("joint", "world"), default="joint",
                   help="axes of the wrench components (default: the child's joint frame)")
    p.add_argument("--method", choices=("auto", "tree", "saddle"), default="auto",
                   help="as for 'hexapod inverse'")
    p.set_defaults(run=cmd_report)

    from hexapod.simulation.registry import DEFAULT_METHOD, INTEGRATORS

    methods = "; ".join(f"{name}: order {cls.order}, index {cls.index}, "
                        f"{'adaptive' if cls.adaptive else 'fixed step'}, {cls.stabilisation}"
                        for name, cls in INTEGRATORS.items())
    p = sub.add_parser(
        "simulate", help="forward dynamics over time: states, multipliers, statistics",
        description="Integrate the motion of SCENE from a consistent start (positions "
        "assembled, velocities projected) and write the directory OUT: results.csv (t, "
        "q:<coordinate>, v:<velocity>, vdot:<velocity>, lambda:<row> and, with --forces or "
        "when the scene sets report_forces, tau/Fx..Tz:<joint> as in 'hexapod inverse'; SI "
        "units), results.npz (the same arrays, compressed) and stats.json (counters, times, "
        "largest constraint violations, energy drift). A run that fails still writes the "
        "states up to the failure, says why and exits with status 1. The directory is "
        "written whole or not at all.")
    _scene_positional(p)
    p.add_argument("--method", choices=list(INTEGRATORS), default=DEFAULT_METHOD,
                   metavar="NAME", help=f"the integrator (default {DEFAULT_METHOD}): {methods}")
    p.add_argument("--t-end", type=_positive(float), metavar="S",
                   help="duration in s (default: one cycle of the scene's periodic laws, or 1 s)")
    p.add_argument("--start", type=float, default=0.0, metavar="S",
                   help="start time in s (default 0)")
    p.add_argument("--rtol", type=_positive(float), default=1e-6,
                   help="relative tolerance of adaptive methods (default 1e-6)")
    p.add_argument("--atol", type=_positive(float), default=1e-8,
                   help="absolute tolerance of adaptive methods, SI units (default 1e-8)")
    p.add_argument("--step", type=_positive(float), metavar="S",
                   help="step of fixed-step methods (default: the duration / 1000), first step "
                   "of adaptive ones (default: chosen)")
    p.add_argument("--every", type=_at_least(1), default=1, metavar="N",
                   help="save every N-th accepted step (default 1; the last state always)")
    p.add_argument("--forces", action="store_true",
                   help="also write every joint's wrench at the saved states")
    p.add_argument("--out", metavar="DIR",
                   help="the directory to write (default: SCENE-NAME-simulation); an earlier "
                   "run there is replaced")
    p.set_defaults(run=cmd_simulate)

    p = sub.add_parser(
        "check", help="where each integrator breaks, why, and what to use",
        description="Without SCENE: the extreme-case suite. Every integrator runs on stiff "
        "springs (1e3 to 1e9 N/m) and a stiff flyball governor, extreme mass ratios (1e-6), "
        "singular configurations (a four-bar through its dead points, the N-four-bar through "
        "the pose where its DOF jumps, a stretched leg), redundant constraints (Bricard's "
        "mechanism, the hexapod standing on its feet), a long horizon and very large steps, "
        "each against an independent reference where it has one; the largest stable step of "
        "the explicit methods is predicted from the linearised modes and measured on stiff "
        "springs. With SCENE: the diagnostics of SCENE at its start and every integrator on "
        "it. Writes the directory OUT: check.md (what to use per case, the diagnostics, the "
        "stable steps, every run: finished or failed and why, steps, rejected steps, CPU time, "
        "constraint drift, energy error, error, condition number along the run), runs.csv, "
        "diagnostics.json, stability.csv and the figures outcomes.png, stability.png and "
        "condition.png, written whole or not at all.")
    p.add_argument("scene", nargs="?", metavar="SCENE",
                   help="a scene file or built-in scene (default: the extreme-case suite)")
    p.add_argument("--methods", nargs="+", choices=list(INTEGRATORS), metavar="NAME",
                   help="integrators to run (default: all)")
    p.add_argument("--t-end", type=_positive(float), metavar="S",
                   help="duration of the runs on SCENE in s (default: one cycle of its "
                   "periodic laws, or 1 s)")
    p.add_argument("--quick", action="store_true",
                   help="shorter runs and fewer stiffnesses (the suite in about 25 minutes "
                   "on 2 cores, with --budget 20)")
    p.add_argument("--budget", type=_positive(float), default=60.0, metavar="S",
                   help="CPU seconds after which a run is stopped, as failed (default 60)")
    p.add_argument("--out", metavar="DIR",
                   help="the directory to write (default: extreme-check, or SCENE-NAME-check)")
    p.set_defaults(run=cmd_check)

    p = sub.add_parser(
        "export", help="VTK files of a simulation or a report, for ParaView",
        description="Turn RESULTS, a directory written by 'hexapod simulate' or 'hexapod "
        "report', into VTK files in the directory DIR: per saved instant bodies_NNNN.vtu (each "
        "body's solid, posed: its equivalent box of inertia and bars to its joints, or the mesh "
        "its scene names or --mesh gives; cell data 'body' and 'part') and joints_NNNN.vtu "
        "(each joint origin with point data 'force' and 'moment' in world axes, the same in "
        "the child's joint frame, and 'effort'); the time indices bodies.pvd and joints.pvd; and "
        "bodies.csv and joints.csv naming the indices. The scene is the one the results "
        "record (a file's path or a built-in scene), or --scene. The directory is written "
        "whole or not at all.")
    p.add_argument("results", metavar="RESULTS",
                   help="a directory written by 'hexapod simulate' or 'hexapod report'")
    p.add_argument("--vtk", required=True, metavar="DIR",
                   help="the directory to write; an earlier export there is replaced when it "
                   "has the same files (the same instants), else refused")
    p.add_argument("--scene", metavar="SCENE",
                   help="the scene the results were computed on (default: the one they record)")
    p.add_argument("--every", type=_at_least(1), default=1, metavar="N",
                   help="export every N-th saved instant, and the last (default 1)")
    p.add_argument("--mesh", action="append", metavar="BODY=FILE",
                   help="draw BODY with a mesh file meshio reads (STL, OBJ, VTU ...), given "
                   "in the body's centre-of-mass frame in metres; repeatable")
    p.set_defaults(run=cmd_export)

    from hexapod.benchmarks.work_precision import PROBLEMS

    p = sub.add_parser(
        "bench", help="work-precision study: error against CPU time of every integrator",
        description="Run every integrator over a ladder of tolerances (adaptive methods) or "
        "steps (fixed-step ones) on Andrews' squeezing mechanism, the closed-loop pendulum "
        "of Richard, Anderson and Andrews, a pendulum over 100 periods and the front leg "
        "falling, each against its "
        "reference, and write OUT: work_precision.md (the CPU time to reach 1e-6 and 1e-9 "
        "relative error in positions, per method and problem; the check of Andrews' forces at "
        "joint E against the published multipliers), runs.csv (every run), work_precision.png "
        "(error against CPU time) and drift_<problem>.png (constraint drift and energy error "
        "against time). Run it from a checkout of the project (it reads data/).")
    p.add_argument("--problems", nargs="+", choices=PROBLEMS, default=list(PROBLEMS),
                   metavar="NAME", help=f"problems (default all: {', '.join(PROBLEMS)})")
    p.add_argument("--methods", nargs="+", choices=list(INTEGRATORS), metavar="NAME",
                   help="integrators (default: all)")
    p.add_argument("--quick", action="store_true",
                   help="shorter horizons and ladders (a first look, a few minutes)")
    p.add_argument("--budget", type=_positive(float), default=30.0, metavar="S",
                   help="stop a method's ladder after a run costing more CPU than this "
                   "(default 30 s)")
    p.add_argument("--data", default="data", metavar="DIR",
                   help="the project's data directory (default: data)")
    p.add_argument("--out", default="work-precision", metavar="DIR",
                   help="the directory to write (default: work-precision)")
    p.set_defaults(run=cmd_bench)

    p = sub.add_parser("validate", help="check a scene and list every problem",
                       description="Read SCENE and report every problem found, or that it is "
                       "valid.")
    p.add_argument("scene", help="a TOML scene file or a built-in scene name")
    p.set_defaults(run=cmd_validate)

    p = sub.add_parser("scenes", help="list the built-in scenes, or write one to a file",
                       description="List the built-in scenes, usable wherever a SCENE is "
                       "asked; with NAME and --write, write that scene as a TOML file.")
    p.add_argument("name", nargs="?", help="a built-in scene (or a scene file) to write")
    p.add_argument("--write", metavar="PATH", help="the TOML file to write")
    p.set_defaults(run=cmd_scenes)
    return parser


def main(argv: list[str] | None = None) -> int:
    import signal
    import threading

    # SIGTERM (kill, a CI timeout) interrupts like Ctrl-C, so that a file being written is
    # removed rather than left behind half-written
    in_main_thread = threading.current_thread() is threading.main_thread()
    if in_main_thread:
        terminate = signal.signal(signal.SIGTERM, signal.default_int_handler)
    try:
        args = build_parser().parse_args(argv)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", MotionWarning)
            try:
                return args.run(args)
            finally:
                for message in dict.fromkeys(str(w.message) for w in caught):
                    print(f"hexapod: warning: {message}", file=sys.stderr)
    except HexapodError as error:
        print(f"hexapod: error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("hexapod: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into a reader that stopped (e.g. head): not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except Exception as error:  # an internal error: still one line unless debugging
        if os.environ.get("HEXAPOD_DEBUG"):
            raise
        print(f"hexapod: internal error: {type(error).__name__}: {error} "
              "(set HEXAPOD_DEBUG=1 for the traceback)", file=sys.stderr)
        return 3
    finally:
        if in_main_thread:
            signal.signal(signal.SIGTERM, terminate)

