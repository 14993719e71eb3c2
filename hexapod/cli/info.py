"""``hexapod info``: what a scene holds and how it was built."""

from __future__ import annotations

from hexapod.cli.common import (
    base_argument,
    emit,
    ground_arguments,
    scene_arguments,
    scene_of,
)

HELP = ("what a scene holds and how it was built: rows, topology, degrees of freedom, "
        "redundancy, condition number")
DESCRIPTION = (
    "Describe SCENE: its bodies, joints, drivers and force elements; what the model was built "
    "with (coordinates per body, rows per joint and driver, force terms); its loops; degrees of "
    "freedom counted (Grubler-Kutzbach) and numerical (n_v - rank Phi_v); the redundant rows and "
    "the condition number at the pose assembled at time T; its total mass; for a walking scene, "
    "the ground-force policy.")


def add_arguments(parser) -> None:
    scene_arguments(parser, "print the description as JSON")
    parser.add_argument("--graph", action="store_true",
                        help="add the vector-network graph of Richard, Anderson and Andrews "
                        "(1989): its edges and its incidence, cutset and circuit matrices")
    ground_arguments(parser)
    base_argument(parser)


def run(args) -> int:
    from hexapod.algorithms.assembly import assemble
    from hexapod.output.describe import describe_model, format_model

    model = assemble(scene_of(args, args.scene))
    emit(describe_model(model, args.t, graph=args.graph), args.json, format_model)
    return 0
