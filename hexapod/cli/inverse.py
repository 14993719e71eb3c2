"""``hexapod inverse``: joint efforts and wrenches of a prescribed motion, as CSV."""

from __future__ import annotations

import sys

from hexapod.cli.common import (
    base_argument,
    check_inverse_memory,
    ground_arguments,
    inverse_arguments,
    limit_arguments,
    sample_progress,
    scene_of,
    show_progress,
)
from hexapod.cli.outputs import given_files, output_file

HELP = "joint efforts and wrenches of a prescribed motion, as CSV"
DESCRIPTION = (
    "Inverse dynamics: drive MODEL (a URDF, a scene file or a built-in scene) by MOTION.csv "
    "(columns t, one per joint in rad or m, optional qd:<joint> and qdd:<joint>) and write "
    "OUT.csv: t, then for every joint tau:<joint> (revolute and prismatic) and Fx, Fy, Fz, Tx, "
    "Ty, Tz:<joint>, the wrench by the parent on the child about the joint origin in the child's "
    "joint frame (N, N m); for a scene with foot contacts (a walking robot) then GRx, GRy, "
    "GRz:LEG, the ground's force on each foot in world axes (N, zero in swing; LEG is the "
    "contact's name without '/ground'), and status:LEG, whether the ground can give it (0 "
    "swing, 1 ok, 2 slip, 3 pull). Each column's unit is in OUT.units.json, written "
    "beside it. The files are written whole or not at all.")


def add_arguments(parser) -> None:
    parser.add_argument("model", help="a URDF (.urdf), a TOML scene file or a built-in scene")
    parser.add_argument("--motion", required=True, metavar="MOTION.csv", help="the motion")
    parser.add_argument("--out", required=True, metavar="OUT.csv", help="the CSV to write")
    inverse_arguments(parser, "tree-ordered solve (open trees with every joint driven), the "
                       "compiled phase path (closed loops and feet on the ground) or the exact "
                       "saddle-point solve per sample (any mechanism); default: the fastest that "
                       "applies")
    limit_arguments(parser)
    ground_arguments(parser)
    base_argument(parser)


def run(args) -> int:
    import warnings

    from hexapod.algorithms.assembly import assemble
    from hexapod.algorithms.inverse import inverse_dynamics, motion_model
    from hexapod.output.inverse_csv import units_path, write_inverse_files
    from hexapod.scene.motion import MotionWarning, apply_motion, read_motion

    inputs = given_files(args.model, args.motion)
    out = output_file(args.out, inputs=inputs)
    output_file(units_path(out), inputs=inputs)  # the units sidecar written beside it
    # every estimated derivative is said, once per message (main prints the warnings)
    warnings.simplefilter("always", MotionWarning)
    motion = read_motion(args.motion)
    scene = scene_of(args, args.model)
    driven = apply_motion(scene, motion)
    driven.ground = scene.ground  # the driven copy keeps the scene's ground-force settings
    model = assemble(driven)
    times = motion.times
    check_inverse_memory(model, times.size, args.max_memory,
                         f"give a motion of fewer samples than {args.motion}'s")
    progress = sample_progress("inverse dynamics") if show_progress() else None
    result = inverse_dynamics(model, times, method=args.method, frame=args.frame,
                              progress=progress)
    model = motion_model(model, result)  # a guided scene's laws: the motion found
    write_inverse_files(out, model, result)  # OUT.units.json, then OUT.csv
    if progress is not None:
        print(file=sys.stderr)
    feet = (f", {len(model.contacts)} feet (ground forces by the policy {result.policy})"
            if model.contacts else "")
    print(f"wrote {args.out}: {times.size} samples, {len(model.joints)} joints{feet} "
          f"({result.method} path)")
    return 0
