"""``hexapod report``: the liaison force report of a driven scene."""

from __future__ import annotations

import sys

from hexapod.cli.common import (
    MAX_TIME,
    base_argument,
    check_inverse_memory,
    ground_arguments,
    inverse_arguments,
    limit_arguments,
    sample_progress,
    scene_of,
    scene_positional,
    show_progress,
    window_arguments,
)
from hexapod.cli.outputs import given_files, output_directory, suffixes

HELP = "the liaison force report of a driven scene: CSV, summary, figures"
DESCRIPTION = (
    "Inverse dynamics of SCENE (a scene file or a built-in scene whose drivers prescribe every "
    "degree of freedom) over a time window, written to the directory OUT: inverse.csv (the CSV "
    "of 'hexapod inverse'), summary.md (per joint the peak and RMS force and moment magnitudes, "
    "per driver the peak effort and RMS power, per body the residual of its equations of motion "
    "under the reported wrenches) and the figures forces.png, torques.png, efforts.png and, when "
    "bodies have a 'foot' marker, foot.png; for a robot (joints named LEG/JOINT, or a URDF "
    "robot's limbs) the force, moment and effort figures put the legs side by side, and "
    "--leg-figures adds one sheet of each per leg (forces-L1.png ...). A walking scene (feet "
    "on the ground by contacts) adds the ground's force on each foot to inverse.csv (GRx, GRy, "
    "GRz:LEG and status:LEG), "
    "ground.csv (per foot: normal and tangential force, friction ratio, status), trunk.csv (the "
    "trunk's pose and velocity), the policy, the feet's peaks and any slip or pull to "
    "summary.md, and the figures ground.png, friction.png and gait.png. With --actuators, "
    "each driven joint is checked against its motor (motors.csv, motors.png and the summary's "
    "section). The directory is written whole or not at all.")


def add_arguments(parser) -> None:
    scene_positional(parser)
    parser.add_argument("--out", metavar="DIR",
                        help="the directory to write (default: SCENE-NAME-report); an earlier "
                        "report there is replaced")
    window_arguments(parser)
    parser.add_argument("--no-figures", dest="figures", action="store_false",
                        help="write the tables and the summary only (the figures are a third of "
                        "a walking robot's report time: for scripts and sweeps)")
    parser.add_argument("--leg-figures", action="store_true",
                        help="for a robot, also one sheet per leg of its joints' forces, "
                        "moments (components and magnitude) and efforts with their power "
                        "(forces-L1.png ...; three times the drawing)")
    parser.add_argument("--motion", metavar="MOTION.csv",
                        help="drive the scene's joints by this motion file, as 'hexapod "
                        "inverse' does (columns t, one per joint, optional qd:<joint> and "
                        "qdd:<joint>); the report then spans the motion's samples")
    parser.add_argument("--actuators", metavar="ACTUATORS.toml",
                        help="the driven joints' motors (stall torque and no-load speed, or a "
                        "rated torque and speed; gear ratio; torque constant and winding "
                        "resistance): adds motors.csv, motors.png and the summary's check of "
                        "each joint against its motor's torque-speed envelope, with the "
                        "current and the electrical power and energy")
    inverse_arguments(parser, "as for 'hexapod inverse'")
    limit_arguments(parser)
    ground_arguments(parser)
    base_argument(parser)


def _driven_by_motion(scene, args):
    """``scene`` driven by ``--motion`` (its ground-force settings kept), and the motion's
    sample times; the window options are refused with it (the motion gives the samples)."""
    import warnings

    from hexapod.errors import HexapodError
    from hexapod.scene.motion import MotionWarning, apply_motion, read_motion

    given = [option for option, value in (("--start", args.start or None),
                                          ("--duration", args.duration),
                                          ("--samples", args.samples)) if value is not None]
    if given:
        raise HexapodError(f"{', '.join(given)}: the motion file {args.motion} gives the "
                           "samples; leave these out with --motion")
    warnings.simplefilter("always", MotionWarning)  # every estimated derivative is said
    motion = read_motion(args.motion)
    driven = apply_motion(scene, motion)
    driven.ground = scene.ground  # the driven copy keeps the scene's ground-force settings
    return driven, motion.times


def run(args) -> int:
    import time

    import numpy as np

    from hexapod._support.files import write_directory_atomically
    from hexapod.algorithms.assembly import assemble
    from hexapod.algorithms.inverse import inverse_dynamics, motion_model
    from hexapod.errors import HexapodError
    from hexapod.output.report import RunInfo, walking_headlines
    from hexapod.scene.actuators import read_actuators

    scene = scene_of(args, args.scene)
    actuators = (scene.actuators if args.actuators is None  # a robot description's own
                 else read_actuators(args.actuators))
    out = output_directory(args.out, f"{scene.name}-report",
                           inputs=given_files(args.scene, args.motion, args.actuators),
                           ours=suffixes(".csv", ".md", ".png", ".json"))
    if args.motion is not None:
        scene, times = _driven_by_motion(scene, args)
        model = assemble(scene)
        duration, why = float(times[-1] - times[0]), f"the motion {args.motion}"
        check_inverse_memory(model, times.size, args.max_memory,
                             f"give a motion of fewer samples than {args.motion}'s")
    else:
        model = assemble(scene)
        duration, why = model.time_window(args.duration)
        if duration > MAX_TIME:
            raise HexapodError(f"the scene's cycle, {duration:g} s, is longer than the "
                               f"{MAX_TIME:g} s a report may span: give a shorter --duration")
        samples = 501 if args.samples is None else args.samples
        check_inverse_memory(model, samples, args.max_memory, "ask for fewer --samples")
        times = args.start + np.linspace(0.0, duration, samples)
    if actuators is not None:  # a table that names no driven joint: said before the run
        actuators.assign([model.joints[d.joint].name for d in model.drivers
                          if d.kind == "joint"])
    show = show_progress()
    progress = sample_progress("inverse dynamics") if show else None
    started = time.perf_counter()
    result = inverse_dynamics(model, times, method=args.method, frame=args.frame,
                              progress=progress)
    model = motion_model(model, result)  # a guided scene's laws: the motion found
    run_time = time.perf_counter() - started
    if show and args.figures:
        print("\rdrawing the figures" + " " * 40, end="", file=sys.stderr, flush=True)
    run = RunInfo(scene.name, args.scene, run_time, f"{why}, {duration:g} s")
    files, balance = report_of(model, result, run, figures=args.figures,
                               leg_figures=args.leg_figures, actuators=actuators)
    write_directory_atomically(out, files)
    if show:
        print("\r" + " " * 60 + "\r", end="", file=sys.stderr)
    worst = int(np.argmax(np.linalg.norm(result.force, axis=2).max(axis=0)))
    print(f"wrote {out}/: {', '.join(files)}")
    print(f"{times.size} samples over {duration:g} s ({result.method} path, {run_time:.3g} s); "
          f"largest joint force {np.linalg.norm(result.force[:, worst], axis=1).max():.4g} N "
          f"at {model.joints[worst].name}; body balance within "
          f"{balance.relative().max():.1e} (relative)")
    for line in walking_headlines(model, result):
        print(line)
    return 0


def report_of(model, result, run, *, figures: bool = True, leg_figures: bool = False,
              actuators=None) -> tuple[dict[str, bytes], object]:
    """The report's files of an inverse-dynamics ``result`` (what ``hexapod report`` writes;
    ``hexapod optimize`` writes its optimum's), and the bodies' balance they summarise."""
    from hexapod.algorithms.balance import body_balance
    from hexapod.algorithms.kinematics import marker_trajectories
    from hexapod.output.report import FOOT_MARKER, report_files

    balance = body_balance(model, result.times, result.q, result.v, result.v_dot,
                           result.force, result.torque, result.frame)
    feet = marker_trajectories(model, result.q, FOOT_MARKER)
    return report_files(model, result, balance, run, feet, figures=figures,
                        workers=_figure_workers(leg_figures), leg_figures=leg_figures,
                        actuators=actuators), balance


def _figure_workers(leg_figures: bool) -> int:
    """Processes to draw the figures. The report's 7 sheets in this one: a second process
    would cost its own start (0.3 s of CPU on a slow core, an eighth of the drawing) for some
    1.3 s less wall time, and the report is judged by its CPU. With ``--leg-figures`` (18 more
    sheets, 120 more panels) the processors this process may run on, at most 4: the start is
    then small beside the time saved."""
    import os

    if not leg_figures:
        return 1
    available = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (
        os.cpu_count() or 1)
    return max(1, min(4, available))
