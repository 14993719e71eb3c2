"""``hexapod dynamics``: forward dynamics at one instant."""

from __future__ import annotations

from hexapod.cli.common import (
    base_argument,
    emit,
    ground_arguments,
    scene_arguments,
    scene_of,
)

HELP = ("forward dynamics at one instant: accelerations, multipliers, joint wrenches and driver "
        "efforts")
DESCRIPTION = (
    "Assemble SCENE at time T (positions by Newton's method, velocities projected), solve the "
    "saddle-point system and print the joint wrenches (exerted by the parent on the child, about "
    "the joint origin, in the child's joint frame), the driver efforts, degrees of freedom, "
    "redundant rows and the condition number.")


def add_arguments(parser) -> None:
    scene_arguments(parser, "print the results as JSON")
    ground_arguments(parser)
    base_argument(parser)


def run(args) -> int:
    from hexapod.algorithms.assembly import assemble
    from hexapod.output.describe import describe_state, format_state

    model = assemble(scene_of(args, args.scene))
    emit(describe_state(model, args.t), args.json, format_state)
    return 0
