"""``hexapod scenes``: the built-in scenes, each with what it is; one of them as TOML.

The listing reads each builder's docstring from its module's source rather than importing it,
since the builders' modules load NumPy and CasADi: the list is then as quick as ``--help``.
"""

from __future__ import annotations

import ast
import re
import sys

HELP = "list the built-in scenes, or print or write one as TOML"
DESCRIPTION = (
    "List the built-in scenes, usable wherever a SCENE is asked, each with a line saying what it "
    "is; with NAME, print that scene as a TOML file, or write it to PATH with --write.")


def add_arguments(parser) -> None:
    parser.add_argument("name", nargs="?",
                        help="a built-in scene (or a scene file) to print or write")
    parser.add_argument("--write", metavar="PATH",
                        help="the TOML file to write (default: print the scene on stdout)")


def _module_source(module: str) -> str:
    """The source of ``module`` found without running it, nor the packages above it."""
    from importlib.machinery import PathFinder
    from importlib.util import find_spec

    parts = module.split(".")
    spec = find_spec(parts[0])
    for depth in range(2, len(parts) + 1):
        if spec is None or spec.submodule_search_locations is None:
            break
        spec = PathFinder.find_spec(".".join(parts[:depth]), spec.submodule_search_locations)
    if spec is None or spec.name != module or spec.loader is None:
        raise ImportError(f"no module {module}")
    source = spec.loader.get_source(module)
    if source is None:
        raise ImportError(f"no source for {module}")
    return source


def builder_summary(name: str, entry_point) -> str:
    """What the built-in scene ``name`` is: the summary (first paragraph) of its builder's
    docstring on one line, as plain
    text and without a leading ``Built-in NAME:`` (the name is already said); the builder's
    ``module:function`` when that docstring cannot be read."""
    module, _, function = entry_point.value.partition(":")
    try:
        tree = ast.parse(_module_source(module.strip()))
    except (ImportError, OSError, SyntaxError, ValueError):
        return entry_point.value
    doc = next((ast.get_docstring(node) for node in tree.body
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
                and node.name == function.strip()), None)
    if not doc:
        return entry_point.value
    summary = " ".join(doc.split("\n\n")[0].split())
    line = re.sub(r":\w+:`~?([^`]*)`", r"\1", summary).replace("``", "").strip()
    prefix = f"Built-in {name}: "
    if line.startswith(prefix):
        line = line[len(prefix):]
        line = line[:1].upper() + line[1:]
    return line


def run(args) -> int:
    from hexapod.scene.builtin import DEFAULT_SCENE, builtin_scenes

    if args.name:
        from hexapod.scene.builtin import load_scene
        from hexapod.scene.writer import scene_text, write_scene

        if args.write:
            from hexapod.cli.outputs import given_files, output_file

            output_file(args.write, option="--write", inputs=given_files(args.name))
        scene = load_scene(args.name)
        if not args.write:
            sys.stdout.write(scene_text(scene, header=f"Built-in scene '{args.name}', written by "
                                        f"'hexapod scenes {args.name}'."))
            return 0
        write_scene(scene, args.write, header=f"Built-in scene '{args.name}', written by "
                    f"'hexapod scenes {args.name} --write'.")
        print(f"wrote {args.write}")
        return 0
    scenes = builtin_scenes()
    if not scenes:
        print("no built-in scenes installed")
    for name in sorted(scenes):
        marker = " (default)" if name == DEFAULT_SCENE else ""
        print(f"{name}{marker}: {builder_summary(name, scenes[name])}")
    return 0
