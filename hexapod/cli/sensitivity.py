"""``hexapod sensitivity``: the derivatives of a driven scene's figures of merit with respect to
design parameters."""

from __future__ import annotations

import sys

from hexapod.cli.common import (
    MAX_TIME,
    base_argument,
    check_inverse_memory,
    ground_arguments,
    sample_progress,
    scene_of,
    scene_positional,
    show_progress,
    window_arguments,
)
from hexapod.cli.outputs import given_files, output_directory, suffixes

HELP = "derivatives of the figures of merit with respect to design parameters"
DESCRIPTION = (
    "Design sensitivities of SCENE (a scene file or a built-in scene whose drivers prescribe "
    "every degree of freedom): the inverse dynamics over a window, then the exact derivatives "
    "of every joint effort, joint wrench and ground force with respect to each parameter, and "
    "of the figures of merit (peak and RMS effort per driven joint, peak force and moment per "
    "joint, peak ground force per foot, positive work per stride, cost of transport). "
    "Parameters are scene keys, '*' matching any body or joint: body.NAME.mass and "
    "body.NAME.inertia (each component, or body.NAME.inertia.K); a joint's position, "
    "joint.NAME.origin[.K] or joint.NAME.parent_frame.position[.K] (a segment's length; "
    "child_frame on the child); ground.mu, the friction policy's "
    "coefficient; the gait's period, step height, duty factor and stride, gait.period, "
    "gait.step_height, gait.duty and gait.stride (period and step_height, the built-in "
    "walking robot's builder arguments; gait.duty keeps the stride and period, gait.stride "
    "the period and duty); "
    "geometric_scale, every length times s, masses s^3 and inertias s^5 (relative: 1); and "
    "payload, the load the trunk carries (a body's payload key). "
    "Writes the "
    "directory OUT: "
    "sensitivities.csv (metric, parameter, value: the derivative, unit, elasticity (p / m) "
    "dm/dp), units.json, summary.md and one tornado figure of elasticities per family of "
    "figures of merit (tornado-FAMILY.png, its largest element); with --per-sample also "
    "derivatives.npz, every derivative at every sample. The directory is written "
    "whole or not at all.")


def add_arguments(parser) -> None:
    scene_positional(parser)
    parser.add_argument("--parameters", nargs="+", required=True, metavar="KEY",
                        help="scene keys, '*' matching any body or joint name: "
                        "body.NAME.mass, body.NAME.inertia[.K], joint.NAME.origin[.K], "
                        "joint.NAME.parent_frame.position[.K], ground.mu, gait.period, "
                        "gait.step_height, gait.duty, gait.stride, geometric_scale, payload (quote "
                        "the '*' in a shell)")
    parser.add_argument("--metrics", nargs="+", metavar="FAMILY",
                        help="families of figures of merit (default: all: peak_effort, "
                        "rms_effort, peak_force, peak_moment, peak_ground, energy, "
                        "cost_of_transport)")
    parser.add_argument("--out", metavar="DIR",
                        help="the directory to write (default: SCENE-NAME-sensitivity); an "
                        "earlier one there is replaced")
    window_arguments(parser, 501)
    parser.add_argument("--no-figures", dest="figures", action="store_false",
                        help="write the table and the summary only")
    parser.add_argument("--per-sample", action="store_true",
                        help="also derivatives.npz: every effort's, joint wrench's, ground "
                        "force's and position's derivative at every sample (docs/design.md)")
    parser.add_argument("--method", choices=("auto", "tree", "phase", "saddle"),
                        default="auto", help="the inverse dynamics' path (as for 'hexapod "
                        "report'; the derivatives do not depend on it)")
    ground_arguments(parser)
    base_argument(parser)


def run(args) -> int:
    from hexapod._support.files import write_directory_atomically
    from hexapod.algorithms.assembly import assemble
    from hexapod.errors import HexapodError
    from hexapod.output.sensitivity import (
        SENSITIVITY_COLUMNS,
        sensitivity_csv_text,
        sensitivity_summary,
        tornado_metrics,
    )
    from hexapod.simulation.results import units_json
    from hexapod.sweeps.design import check_families, sensitivity_run
    from hexapod.sweeps.design_parameters import inertia_parameters
    from hexapod.sweeps.metric_derivatives import SENSITIVE_FAMILIES

    scene = scene_of(args, args.scene)
    families = check_families(args.metrics or SENSITIVE_FAMILIES)
    changes = inertia_parameters(scene, args.parameters)  # refused before any output
    out = output_directory(args.out, f"{scene.name}-sensitivity",
                           inputs=given_files(args.scene),
                           ours=suffixes(".csv", ".md", ".png", ".json", ".npz"))
    if args.duration is not None and args.duration > MAX_TIME:
        raise HexapodError(f"--duration {args.duration:g} s is longer than the {MAX_TIME:g} s "
                           "a run may span")
    progress = ((lambda stage, done, total: sample_progress(stage)(done, total))
                if show_progress() else None)
    model = assemble(scene)
    check_inverse_memory(model, args.samples, None, "ask for fewer --samples")
    run = sensitivity_run(scene, changes, families=families, samples=args.samples,
                          start=args.start, duration=args.duration, method=args.method,
                          progress=progress, model=model)
    chosen = tornado_metrics(run.metrics, run.derivatives)
    files = {"sensitivities.csv": sensitivity_csv_text(run.rows).encode(),
             "units.json": units_json({"sensitivities.csv": SENSITIVITY_COLUMNS}).encode(),
             "summary.md": sensitivity_summary(scene.name, run.metrics, run.rows, chosen,
                                               args.samples, run.run_time,
                                               run.sensitivity.active_set_changes,
                                               int(run.result.infeasible.sum())).encode()}
    if args.figures:
        files.update(_figures(run, chosen))
    if args.per_sample:
        from hexapod.output.sensitivity import derivatives_npz_bytes

        files["derivatives.npz"] = derivatives_npz_bytes(run.model, run.result, run.sensitivity)
    write_directory_atomically(out, files)
    if progress is not None:
        print("\r" + " " * 60 + "\r", end="", file=sys.stderr)
    print(f"wrote {out}/: {', '.join(files)}")
    print(f"{len(run.sensitivity.parameters)} parameters, {len(run.derivatives)} figures of "
          f"merit, {args.samples} samples ({run.result.method} path, {run.run_time:.3g} s CPU)")
    if not run.result.feasible:
        print(f"infeasible at {int(run.result.infeasible.sum())} samples: the ground cannot "
              "give the feet their forces (a foot slips or is pulled); see summary.md")
    return 0


def _figures(run, chosen: dict[str, str]) -> dict[str, bytes]:
    from hexapod.output.figures import png_bytes
    from hexapod.output.sensitivity import tornado_figure
    from hexapod.sweeps.metrics import metric_unit

    return {f"tornado-{family}.png": png_bytes(tornado_figure(
                run.rows, metric, run.metrics[metric], metric_unit(run.model, metric)))
            for family, metric in chosen.items()}
