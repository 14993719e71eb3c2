"""``hexapod optimize``: a figure of merit minimised over masses and inertias."""

from __future__ import annotations

import sys

from hexapod.cli.common import show_progress
from hexapod.cli.outputs import given_files, output_directory, suffixes

HELP = "minimise a figure of merit over masses, inertias and joints' positions"
DESCRIPTION = (
    "Design optimisation of a study file (STUDY.toml, the sweep's format: [study] scene, "
    "[fixed] held values, [job] the inverse-dynamics window; [vary.KEY] each parameter's "
    "bounds as range = [low, high] and an optional start; [optimize] minimize = FIGURE and "
    "constraints = { FIGURE = { min = A, max = B } }, '*' matching any joint or foot, and "
    "actuators = TABLE.toml to keep every driven joint's peak effort below its motor's): IPOPT "
    "through CasADi with the exact gradients of 'hexapod sensitivity'. Writes the directory "
    "OUT: optimization.csv (every evaluation: the figure, the constraints' excess, the "
    "parameters), optimum.csv, optimum.toml (the scene at the optimum), optimization.png, "
    "summary.md, and the optimum's report (optimum-summary.md, optimum-inverse.csv and its "
    "figures, as 'hexapod report' writes them). The directory is written whole or not at all.")


def add_arguments(parser) -> None:
    parser.add_argument("study", metavar="STUDY.toml", help="the optimisation study")
    parser.add_argument("--out", metavar="DIR",
                        help="the directory to write (default: STUDY-NAME-optimum); an earlier "
                        "one there is replaced")
    parser.add_argument("--no-figures", dest="figures", action="store_false",
                        help="write the tables and the summaries only")


def run(args) -> int:
    import json

    from hexapod._support.files import write_directory_atomically
    from hexapod.cli.report import report_of
    from hexapod.output.optimization import (
        OPTIMUM_COLUMNS,
        convergence_figure,
        log_columns,
        log_csv_text,
        optimization_summary,
        optimum_csv_text,
    )
    from hexapod.output.report import RunInfo
    from hexapod.scene.writer import scene_text
    from hexapod.simulation.results import units_json
    from hexapod.sweeps.metrics import metric_unit
    from hexapod.sweeps.optimize import optimize, read_optimization

    spec = read_optimization(args.study)
    out = output_directory(args.out, f"{spec.study.name}-optimum",
                           inputs=given_files(args.study, spec.study.scene),
                           ours=suffixes(".csv", ".md", ".png", ".json", ".toml"))
    say = (lambda line: print(f"\r{line[:70]:<70}", end="", file=sys.stderr, flush=True)) \
        if show_progress() else None
    run = optimize(spec, progress=say)
    unit = metric_unit(run.optimum_model, spec.minimize)
    report, _ = report_of(run.optimum_model, run.optimum_result,
                          RunInfo(f"{spec.study.name} optimum", "optimum.toml", 0.0,
                                  "the study's window"), figures=args.figures)
    tables = {"optimization.csv": log_columns(run, unit), "optimum.csv": OPTIMUM_COLUMNS}
    for name, columns in json.loads(report.pop("units.json")).items():
        tables[f"optimum-{name}"] = {c: (d["unit"], d["quantity"]) for c, d in columns.items()}
    files = {"optimization.csv": log_csv_text(run).encode(),
             "optimum.csv": optimum_csv_text(run).encode(),
             "optimum.toml": scene_text(run.optimum_scene).encode(),
             "summary.md": optimization_summary(run, unit).encode(),
             "units.json": units_json(tables).encode()}
    if args.figures:
        from hexapod.output.figures import png_bytes

        files["optimization.png"] = png_bytes(convergence_figure(run, unit))
    files |= {f"optimum-{name}": content for name, content in report.items()}
    write_directory_atomically(out, files)
    if say is not None:
        print("\r" + " " * 72 + "\r", end="", file=sys.stderr)
    values = ", ".join(f"{c.name} = {v:.10g} {c.unit}"
                       for c, v in zip(run.parameters, run.optimum, strict=True))
    print(f"wrote {out}/: {len(files)} files")
    print(f"{run.status} in {run.iterations} iterations: {spec.minimize} = "
          f"{run.checked[spec.minimize]:.10g} {unit} at {values}")
    if not run.success:
        print(f"IPOPT did not converge ({run.status}): the optimum is its last iterate",
              file=sys.stderr)
        return 1
    return 0
