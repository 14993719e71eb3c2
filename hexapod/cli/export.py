"""``hexapod export``: VTK files of a simulation or a report, for ParaView."""

from __future__ import annotations

import argparse

from hexapod._support.limits import parse_size
from hexapod.cli.common import at_least
from hexapod.cli.outputs import given_files, output_directory, suffixes

HELP = "VTK files of a simulation or a report, for ParaView"
DESCRIPTION = (
    "Turn RESULTS, a directory written by 'hexapod simulate' or 'hexapod report', into VTK files "
    "in the directory DIR: per saved instant bodies_NNNN.vtu (each body's solid, posed: its "
    "equivalent box of inertia and bars to its joints, or the mesh its scene names or --mesh "
    "gives; cell data 'body' and 'part') and joints_NNNN.vtu (each joint origin with point data "
    "'force' and 'moment' in world axes, the same in the child's joint frame, and 'effort'); for "
    "a walking scene feet_NNNN.vtu (each foot's point with point data 'ground_force', the "
    "ground's force on the foot in world axes, N, zero in swing, for ParaView's Glyph filter, "
    "and 'stance'); the time indices bodies.pvd, joints.pvd (and feet.pvd); and bodies.csv and "
    "joints.csv (and feet.csv) naming the indices. "
    "The scene is the one the results record (a file's path or a built-in scene), or --scene. "
    "The directory is written whole or not at all.")


def add_arguments(parser) -> None:
    parser.add_argument("results", metavar="RESULTS",
                        help="a directory written by 'hexapod simulate' or 'hexapod report'")
    parser.add_argument("--vtk", required=True, metavar="DIR",
                        help="the directory to write; an earlier export there is replaced when "
                        "it has the same files (the same instants), else refused")
    parser.add_argument("--scene", metavar="SCENE",
                        help="the scene the results were computed on (default: the one they "
                        "record)")
    parser.add_argument("--every", type=at_least(1), default=1, metavar="N",
                        help="export every N-th saved instant, and the last (default 1)")
    parser.add_argument("--mesh", action="append", metavar="BODY=FILE",
                        help="draw BODY with a mesh file meshio reads (STL, OBJ, VTU ...), given "
                        "in the body's centre-of-mass frame in metres; repeatable")
    parser.add_argument("--max-instants", type=at_least(1), metavar="N",
                        help="the most saved instants read (default: the environment variable "
                        "HEXAPOD_MAX_INSTANTS, else 20000)")
    parser.add_argument("--max-mesh-size", type=mesh_size, metavar="SIZE",
                        help="the largest mesh file read for a body, e.g. 512M or 2G (default: "
                        "the environment variable HEXAPOD_MAX_MESH_BYTES, else 256M)")


def mesh_size(text: str) -> int:
    """An argparse type: a size in bytes, written 512M, 2G or 1000000."""
    try:
        return parse_size(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def run(args) -> int:
    from hexapod._support.files import write_directory_atomically
    from hexapod._support.limits import check_instants
    from hexapod.algorithms.assembly import assemble
    from hexapod.errors import InputFileError
    from hexapod.output.recording import read_recording
    from hexapod.output.vtk import frames, read_mesh, scene_meshes, vtk_files
    from hexapod.scene.builtin import load_scene

    out = output_directory(args.vtk, "", option="--vtk",
                           inputs=given_files(args.results, args.scene, *(
                               item.partition("=")[2] for item in args.mesh or [])),
                           ours=suffixes(".vtu", ".pvd", ".csv", ".json"))
    recording = read_recording(args.results, weigh=lambda count: check_instants(
        count, f"{args.results}", args.max_instants))
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
    meshes = scene_meshes(scene, args.max_mesh_size)
    for item in args.mesh or []:
        body, sep, path = item.partition("=")
        if not sep or not body or not path:
            raise InputFileError(f"--mesh {item}: expected BODY=FILE")
        try:
            meshes[body] = read_mesh(path, args.max_mesh_size)
        except InputFileError as error:
            raise InputFileError(f"--mesh, body '{body}': {error}") from None
    model = assemble(scene)
    files = vtk_files(model, frames(model, recording), meshes, every=args.every)
    write_directory_atomically(out, files)
    count = sum(name.startswith("bodies_") for name in files)
    indices = [name for name in files if name.endswith(".pvd")]
    print(f"wrote {out}/: {count} instants of {recording.kind} '{scene.name}' over t = "
          f"{recording.t[0]:g} ... {recording.t[-1]:g} s, {len(files)} files; open "
          f"{' and '.join(indices)} in ParaView")
    return 0
