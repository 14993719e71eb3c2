"""``hexapod simulate``: forward dynamics over time."""

from __future__ import annotations

import json
import sys

from hexapod.cli.common import (
    MAX_TIME,
    at_least,
    base_argument,
    compile_argument,
    ground_arguments,
    jsonable,
    limit_arguments,
    output_times,
    positive,
    relative_tolerance,
    scene_of,
    scene_positional,
    seconds,
    short,
    show_progress,
    time_progress,
    time_value,
)
from hexapod.cli.outputs import given_files, output_directory, suffixes
from hexapod.simulation.methods import (
    ALL_METHODS,
    ATOL_KINDS,
    CONTACT_METHODS,
    DEFAULT_ATOL,
    DEFAULT_METHOD,
    DEFAULT_RTOL,
    aliases_of,
    resolve_method,
)

HELP = "forward dynamics over time: states, multipliers, statistics"
DESCRIPTION = (
    "Integrate the motion of SCENE from a consistent start (positions assembled, velocities "
    "projected) and write the directory OUT: results.csv (t, q:<coordinate>, v:<velocity>, "
    "vdot:<velocity>, lambda:<row> and, with --forces or when the scene sets report_forces, "
    "tau/Fx..Tz:<joint> as in 'hexapod inverse'; SI units), units.json (each column's unit), "
    "results.npz (the same arrays, compressed) and stats.json (status, time reached, counters, "
    "times, largest constraint violations, energy drift). With unilateral contacts (a "
    "contact scheme) results.csv also has the ground's force at each contact (GRx..GRz:<leg>, "
    "world axes, N, named as in 'hexapod inverse') and the directory events.csv (t, kind: "
    "touch-down, lift-off, slip-start, slip-end or impact, contact, the impulse Px..Pz in N s), "
    "contacts.png (the ground forces, pushed states shaded) and gait.png (when each contact "
    "pushes); with joint controllers, err:<controller> columns (rad) and tracking.png. "
    "With --t-eval or --dt-out the "
    "states are saved at those times only, from each method's own dense output. A run that "
    "fails, passes "
    "--cpu-budget or is interrupted (Ctrl-C, SIGTERM) still writes the states up to there, "
    "marked so in stats.json, says why and exits with status 1 (130, 143 when interrupted). The "
    "directory is written whole or not at all.")


#: the per-kind absolute tolerances' options: kind -> (unit, what)
ATOL_OPTIONS = {"position": ("m", "positions of centres of mass and particles"),
                "angle": ("rad", "angles of planar bodies and Euler parameters"),
                "velocity": ("m/s", "velocities of centres of mass and particles"),
                "angular_velocity": ("rad/s", "angular velocities")}


def add_arguments(parser) -> None:
    methods = "; ".join(
        f"{name}: {method.summary()}"
        + "".join(f" (short name {alias})" for alias in aliases_of(name))
        for name, method in ALL_METHODS.items())
    scene_positional(parser)
    parser.add_argument("--method", type=resolve_method, choices=list(ALL_METHODS),
                        metavar="NAME",
                        help=f"the integrator, by name or short name (default {DEFAULT_METHOD}"
                        f", or {next(iter(CONTACT_METHODS))} for a scene with unilateral "
                        f"contacts): {methods}")
    parser.add_argument("--t-end", type=seconds, metavar="S",
                        help="duration in s (default: one cycle of the scene's periodic laws, "
                        "or 1 s)")
    parser.add_argument("--start", type=time_value, default=0.0, metavar="S",
                        help="start time in s (default 0)")
    parser.add_argument("--rtol", type=relative_tolerance,
                        help="relative tolerance of adaptive methods (default "
                        f"{short(DEFAULT_RTOL)})")
    parser.add_argument("--atol", type=positive(float),
                        help="absolute tolerance of adaptive methods, SI units, for every kind "
                        f"of coordinate (default {short(DEFAULT_ATOL)})")
    kinds = parser.add_argument_group(
        "absolute tolerances per kind",
        "each overrides --atol for one kind of coordinate; the kinds not given take --atol or, "
        f"without it, their defaults: {short(DEFAULT_ATOL)} L for positions (L the scene's "
        f"characteristic length), {short(DEFAULT_ATOL)} rad for angles, and their rates the "
        "same per characteristic time sqrt(L / g) (1 s without gravity)")
    for kind, (unit, what) in ATOL_OPTIONS.items():
        kinds.add_argument("--atol-" + kind.replace("_", "-"), type=positive(float),
                           metavar=unit.upper().replace("/", "_PER_"),
                           help=f"absolute tolerance of the {what}, {unit}")
    parser.add_argument("--step", type=seconds, metavar="S",
                        help="step of fixed-step methods (default: the duration / 1000), first "
                        "step of adaptive ones (default: chosen)")
    saved = parser.add_mutually_exclusive_group()
    saved.add_argument("--every", type=at_least(1), metavar="N",
                       help="save every N-th accepted step (default 1; the last state always)")
    saved.add_argument("--t-eval", type=output_times, metavar="T0,T1,...",
                       help="save the states at these times only (s, increasing, within the "
                       "run; @FILE: one time a line), each from the method's own dense output "
                       "over the step that holds it, projected onto the constraints; the steps "
                       "are not changed")
    saved.add_argument("--dt-out", type=seconds, metavar="S",
                       help="save the states every S seconds from the start (the end too when "
                       "the duration is a multiple of S), as --t-eval does")
    parser.add_argument("--forces", action="store_true",
                        help="also write every joint's wrench at the saved states")
    parser.add_argument("--out", metavar="DIR",
                        help="the directory to write (default: SCENE-NAME-simulation); an "
                        "earlier run there is replaced")
    parser.add_argument("--cpu-budget", type=seconds, metavar="S",
                        help="stop the run, as failed, after this many CPU seconds in its time "
                        "loop; the states up to there are written (default: no budget)")
    parser.add_argument("--exact-laws", action="store_true",
                        help="evaluate every time law exactly at every stage (default: laws "
                        "that cost far more than a table, a gait's inverse kinematics, are "
                        "tabulated once and interpolated to a hundredth of --rtol; stats.json "
                        "says how, under options.laws)")
    parser.add_argument("--bandwidth", type=positive(float), metavar="HZ",
                        help="the joint controllers' gains by the rule 'critically damped on "
                        "each joint's reflected inertia' at the start's pose (the other joints "
                        "locked, the feet in the air): kp = I w^2, kd = 2 I w with w = 2 pi HZ, "
                        "in place of the scene's kp and kd")
    compile_argument(parser, "the integrators' kernels (the right-hand side and the "
                     "projection, one per set of feet down)")
    limit_arguments(parser, steps=True)
    ground_arguments(parser)
    base_argument(parser)


def run(args) -> int:
    from hexapod._support.files import write_directory_atomically
    from hexapod.algorithms.assembly import assemble
    from hexapod.simulation.loop import simulate
    from hexapod.simulation.registry import default_method
    from hexapod.simulation.results import EVENT_COLUMNS, scene_reference, units_json

    scene = scene_of(args, args.scene)
    out = output_directory(args.out, f"{scene.name}-simulation",
                           inputs=given_files(args.scene),
                           ours=suffixes(".csv", ".npz", ".json"))
    model = assemble(scene)
    if args.bandwidth is not None:
        scene = _critically_damped(scene, model, args.bandwidth, args.start)
        model = assemble(scene)
    args.method = args.method or default_method(model)
    duration, why = model.time_window(args.t_end)
    _check_step(args, duration)
    try:
        grid = _output_grid(args, model, duration)
    except _OptionError as error:
        print(f"hexapod simulate: error: {error}", file=sys.stderr)
        return 2
    show = show_progress()
    result = simulate(model, args.start + duration, t0=args.start, method=args.method,
                      rtol=args.rtol, atol=_absolute_tolerance(args), step=args.step,
                      every=args.every or 1, t_eval=grid,
                      forces=True if args.forces else None,
                      progress=time_progress(args.method, args.start) if show else None,
                      max_steps=args.max_steps, max_memory=args.max_memory,
                      cpu_budget=args.cpu_budget, advice=_advice(args),
                      exact_laws=args.exact_laws)
    result.source = scene_reference(args.scene)  # for 'hexapod export'
    if show:
        print("\r" + " " * 90 + "\r", end="", file=sys.stderr)
    stats = result.statistics()
    files = {"results.csv": result.csv_text().encode(), "results.npz": result.npz_bytes(),
             "units.json": units_json({"results.csv": result.column_units()}).encode(),
             "stats.json": (json.dumps(jsonable(stats), indent=2) + "\n").encode()}
    if result.events is not None or result.tracking is not None:  # contacts, controllers
        from hexapod.output.contact_figures import (
            contact_figure_builders,
            tracking_figure_builders,
        )
        from hexapod.output.figures import render_figures

        if result.events is not None:
            files["events.csv"] = result.events_csv_text().encode()
            files["units.json"] = units_json({"results.csv": result.column_units(),
                                              "events.csv": EVENT_COLUMNS}).encode()
        files.update(render_figures({**contact_figure_builders(result),
                                     **tracking_figure_builders(result)}))
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


def _critically_damped(scene, model, bandwidth: float, start: float):
    """``scene`` with each joint controller's gains by the rule of ``--bandwidth``
    (:func:`hexapod.simulation.critical_gains` at the positions the run starts from)."""
    import dataclasses

    from hexapod.algorithms.joint_inertia import critical_gains
    from hexapod.algorithms.kinematics import assemble_positions
    from hexapod.errors import HexapodError
    from hexapod.scene import JointController

    if not any(isinstance(f, JointController) for f in scene.forces.values()):
        raise HexapodError(f"--bandwidth: scene '{scene.name}' has no joint controllers "
                           "(type = \"controller\" force elements) to tune")
    kp, kd = critical_gains(model, assemble_positions(model, model.create_data(), start),
                            bandwidth)
    for e in scene.forces.values():
        if isinstance(e, JointController) and e.joint not in kp:
            raise HexapodError(f"--bandwidth: controller '{e.name}': joint '{e.joint}' has no "
                               "reflected inertia of its own (in a closed loop, or without "
                               "an axis): give its kp and kd in the scene")
    to_scene = 1.0 / scene.unit  # N m per rad to the scene's N L per rad
    return scene.with_elements(
        dataclasses.replace(e, kp=kp[e.joint] * to_scene, kd=kd[e.joint] * to_scene)
        if isinstance(e, JointController) else e for e in scene.elements)


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


class _OptionError(Exception):
    """A value of an option that does not fit the run (status 2, as argparse's errors)."""


def _output_grid(args, model, duration: float):
    """The output times of ``--t-eval`` or ``--dt-out`` (None without either), checked against
    the run (within it, at most the limits of steps and memory) before any array of them is
    made; an :class:`_OptionError` naming the option."""
    from hexapod.cli.common import TimesFile, read_times
    from hexapod.errors import HexapodError
    from hexapod.simulation.loop import (
        output_times,
        uniform_count,
        uniform_times,
        weigh_output_times,
    )

    if args.t_eval is None and args.dt_out is None:
        return None
    option = "--t-eval" if args.t_eval is not None else "--dt-out"
    start, end = args.start, args.start + duration
    try:
        if args.dt_out is not None:
            if args.dt_out > duration:
                raise ValueError(f"{args.dt_out:g} s is longer than the run ({duration:g} s)")
            count = uniform_count(start, end, args.dt_out)
            weigh_output_times(model, count, args.max_steps, args.max_memory, _advice(args))
            return uniform_times(start, end, args.dt_out)
        times = args.t_eval
        if isinstance(times, TimesFile):
            from hexapod._support.limits import max_steps

            times = read_times(times, max_steps(args.max_steps))
        weigh_output_times(model, len(times), args.max_steps, args.max_memory, _advice(args))
        return output_times(times, start, end)
    except (ValueError, HexapodError) as error:
        raise _OptionError(f"argument {option}: {error}") from None


def _absolute_tolerance(args):
    """``--atol`` (a number, or None), or with options per kind the mapping of the kinds
    given: those not given take ``--atol`` when it is, else their own defaults."""
    given = {kind: getattr(args, "atol_" + kind) for kind in ATOL_KINDS
             if getattr(args, "atol_" + kind, None) is not None}
    if not given:
        return args.atol
    base = dict.fromkeys(ATOL_KINDS, args.atol) if args.atol is not None else {}
    return {**base, **given}


def _advice(args) -> dict[str, str]:
    """What the messages of the limits suggest, in this command's options."""
    if ALL_METHODS[args.method].adaptive:
        steps = "shorten --t-end, or loosen --rtol and --atol"
    else:
        steps = "shorten --t-end, or give a larger --step"
    return {"steps": steps, "memory": "save fewer states with a larger --every N",
            "output": "give fewer times with --t-eval, or a larger --dt-out"}
