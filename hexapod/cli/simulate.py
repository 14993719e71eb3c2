"""``hexapod simulate``: forward dynamics over time."""

from __future__ import annotations

import json
import sys

from hexapod.cli.common import (
    MAX_TIME,
    apply_ground_options,
    at_least,
    ground_arguments,
    jsonable,
    limit_arguments,
    positive,
    relative_tolerance,
    scene_positional,
    seconds,
    short,
    time_progress,
    time_value,
)
from hexapod.cli.outputs import given_files, output_directory, suffixes
from hexapod.simulation.methods import DEFAULT_ATOL, DEFAULT_METHOD, DEFAULT_RTOL, METHODS

HELP = "forward dynamics over time: states, multipliers, statistics"
DESCRIPTION = (
    "Integrate the motion of SCENE from a consistent start (positions assembled, velocities "
    "projected) and write the directory OUT: results.csv (t, q:<coordinate>, v:<velocity>, "
    "vdot:<velocity>, lambda:<row> and, with --forces or when the scene sets report_forces, "
    "tau/Fx..Tz:<joint> as in 'hexapod inverse'; SI units), units.json (each column's unit), "
    "results.npz (the same arrays, compressed) and stats.json (status, time reached, counters, "
    "times, largest constraint violations, energy drift). A run that fails, passes "
    "--cpu-budget or is interrupted (Ctrl-C, SIGTERM) still writes the states up to there, "
    "marked so in stats.json, says why and exits with status 1 (130, 143 when interrupted). The "
    "directory is written whole or not at all.")


def add_arguments(parser) -> None:
    methods = "; ".join(f"{name}: {method.summary()}" for name, method in METHODS.items())
    scene_positional(parser)
    parser.add_argument("--method", choices=list(METHODS), default=DEFAULT_METHOD,
                        metavar="NAME",
                        help=f"the integrator (default {DEFAULT_METHOD}): {methods}")
    parser.add_argument("--t-end", type=seconds, metavar="S",
                        help="duration in s (default: one cycle of the scene's periodic laws, "
                        "or 1 s)")
    parser.add_argument("--start", type=time_value, default=0.0, metavar="S",
                        help="start time in s (default 0)")
    parser.add_argument("--rtol", type=relative_tolerance,
                        help="relative tolerance of adaptive methods (default "
                        f"{short(DEFAULT_RTOL)})")
    parser.add_argument("--atol", type=positive(float),
                        help="absolute tolerance of adaptive methods, SI units (default "
                        f"{short(DEFAULT_ATOL)})")
    parser.add_argument("--step", type=seconds, metavar="S",
                        help="step of fixed-step methods (default: the duration / 1000), first "
                        "step of adaptive ones (default: chosen)")
    parser.add_argument("--every", type=at_least(1), default=1, metavar="N",
                        help="save every N-th accepted step (default 1; the last state always)")
    parser.add_argument("--forces", action="store_true",
                        help="also write every joint's wrench at the saved states")
    parser.add_argument("--out", metavar="DIR",
                        help="the directory to write (default: SCENE-NAME-simulation); an "
                        "earlier run there is replaced")
    parser.add_argument("--cpu-budget", type=seconds, metavar="S",
                        help="stop the run, as failed, after this many CPU seconds in its time "
                        "loop; the states up to there are written (default: no budget)")
    limit_arguments(parser, steps=True)
    ground_arguments(parser)


def run(args) -> int:
    from hexapod._support.files import write_directory_atomically
    from hexapod.model.assemble import assemble
    from hexapod.scene.builtin import load_scene
    from hexapod.simulation.loop import simulate
    from hexapod.simulation.results import scene_reference, units_json

    scene = apply_ground_options(load_scene(args.scene), args)
    out = output_directory(args.out, f"{scene.name}-simulation", inputs=given_files(args.scene),
                           ours=suffixes(".csv", ".npz", ".json"))
    model = assemble(scene)
    duration, why = model.time_window(args.t_end)
    _check_step(args, duration)
    show = sys.stderr.isatty()
    result = simulate(model, args.start + duration, t0=args.start, method=args.method,
                      rtol=args.rtol, atol=args.atol, step=args.step, every=args.every,
                      forces=True if args.forces else None,
                      progress=time_progress(args.method, args.start) if show else None,
                      max_steps=args.max_steps, max_memory=args.max_memory,
                      cpu_budget=args.cpu_budget, advice=_advice(args))
    result.source = scene_reference(args.scene)  # for 'hexapod export'
    if show:
        print("\r" + " " * 90 + "\r", end="", file=sys.stderr)
    stats = result.statistics()
    files = {"results.csv": result.csv_text().encode(), "results.npz": result.npz_bytes(),
             "units.json": units_json({"results.csv": result.column_units()}).encode(),
             "stats.json": (json.dumps(jsonable(stats), indent=2) + "\n").encode()}
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
    if result.status == "interrupted":
        # the states are written; the command ends as interrupted (status 130 or 143, the
        # signal's, set by hexapod.cli.app when it received one)
        print(f"hexapod: {result.message} (the states up to it are in {out}/)",
              file=sys.stderr)
        return 130
    if not result.success:
        print(f"hexapod: error: {result.message} (the states up to it are in {out}/)",
              file=sys.stderr)
        return 1
    return 0


def _check_step(args, duration: float) -> None:
    """The duration (one cycle of the scene's laws when not given) within the times the
    options take, and a step no longer than it: one error naming the options, before any
    work."""
    from hexapod.errors import HexapodError

    if duration > MAX_TIME:
        raise HexapodError(f"the scene's cycle, {duration:g} s, is longer than the {MAX_TIME:g}"
                           " s a run may last: give a shorter --t-end")
    if args.step is not None and args.step > duration:
        span = f"--t-end {args.t_end:g}" if args.t_end is not None else (
            f"the default duration, {duration:g} s")
        raise HexapodError(f"--step {args.step:g} is longer than the run ({span}): give a "
                           "shorter step or a longer --t-end")


def _advice(args) -> dict[str, str]:
    """What the messages of the limits suggest, in this command's options."""
    from hexapod.simulation.methods import METHODS

    if METHODS[args.method].adaptive:
        steps = "shorten --t-end, or loosen --rtol and --atol"
    else:
        steps = "shorten --t-end, or give a larger --step"
    return {"steps": steps, "memory": "save fewer states with a larger --every N"}
