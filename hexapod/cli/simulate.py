"""``hexapod simulate``: forward dynamics over time."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from hexapod.cli.common import (
    apply_ground_options,
    at_least,
    ground_arguments,
    jsonable,
    positive,
    scene_positional,
    short,
    time_progress,
)
from hexapod.simulation.methods import DEFAULT_ATOL, DEFAULT_METHOD, DEFAULT_RTOL, METHODS

HELP = "forward dynamics over time: states, multipliers, statistics"
DESCRIPTION = (
    "Integrate the motion of SCENE from a consistent start (positions assembled, velocities "
    "projected) and write the directory OUT: results.csv (t, q:<coordinate>, v:<velocity>, "
    "vdot:<velocity>, lambda:<row> and, with --forces or when the scene sets report_forces, "
    "tau/Fx..Tz:<joint> as in 'hexapod inverse'; SI units), results.npz (the same arrays, "
    "compressed) and stats.json (counters, times, largest constraint violations, energy drift). "
    "A run that fails still writes the states up to the failure, says why and exits with status "
    "1. The directory is written whole or not at all.")


def add_arguments(parser) -> None:
    methods = "; ".join(f"{name}: {method.summary()}" for name, method in METHODS.items())
    scene_positional(parser)
    parser.add_argument("--method", choices=list(METHODS), default=DEFAULT_METHOD,
                        metavar="NAME",
                        help=f"the integrator (default {DEFAULT_METHOD}): {methods}")
    parser.add_argument("--t-end", type=positive(float), metavar="S",
                        help="duration in s (default: one cycle of the scene's periodic laws, "
                        "or 1 s)")
    parser.add_argument("--start", type=float, default=0.0, metavar="S",
                        help="start time in s (default 0)")
    parser.add_argument("--rtol", type=positive(float),
                        help="relative tolerance of adaptive methods (default "
                        f"{short(DEFAULT_RTOL)})")
    parser.add_argument("--atol", type=positive(float),
                        help="absolute tolerance of adaptive methods, SI units (default "
                        f"{short(DEFAULT_ATOL)})")
    parser.add_argument("--step", type=positive(float), metavar="S",
                        help="step of fixed-step methods (default: the duration / 1000), first "
                        "step of adaptive ones (default: chosen)")
    parser.add_argument("--every", type=at_least(1), default=1, metavar="N",
                        help="save every N-th accepted step (default 1; the last state always)")
    parser.add_argument("--forces", action="store_true",
                        help="also write every joint's wrench at the saved states")
    parser.add_argument("--out", metavar="DIR",
                        help="the directory to write (default: SCENE-NAME-simulation); an "
                        "earlier run there is replaced")
    ground_arguments(parser)


def run(args) -> int:
    from hexapod._support.files import write_directory_atomically
    from hexapod.model.assemble import assemble
    from hexapod.scene.builtin import load_scene
    from hexapod.simulation.loop import simulate
    from hexapod.simulation.results import scene_reference

    scene = apply_ground_options(load_scene(args.scene), args)
    model = assemble(scene)
    duration, why = model.time_window(args.t_end)
    out = Path(args.out or f"{scene.name}-simulation")
    show = sys.stderr.isatty()
    result = simulate(model, args.start + duration, t0=args.start, method=args.method,
                      rtol=args.rtol, atol=args.atol, step=args.step, every=args.every,
                      forces=True if args.forces else None,
                      progress=time_progress(args.method, args.start) if show else None)
    result.source = scene_reference(args.scene)  # for 'hexapod export'
    if show:
        print("\r" + " " * 90 + "\r", end="", file=sys.stderr)
    stats = result.statistics()
    files = {"results.csv": result.csv_text().encode(), "results.npz": result.npz_bytes(),
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
    if not result.success:
        print(f"hexapod: error: {result.message} (the states up to it are in {out}/)",
              file=sys.stderr)
        return 1
    return 0
