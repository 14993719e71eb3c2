"""``hexapod scenes``: the built-in scenes; one of them written as TOML."""

from __future__ import annotations

HELP = "list the built-in scenes, or write one to a file"
DESCRIPTION = ("List the built-in scenes, usable wherever a SCENE is asked; with NAME and "
               "--write, write that scene as a TOML file.")


def add_arguments(parser) -> None:
    parser.add_argument("name", nargs="?", help="a built-in scene (or a scene file) to write")
    parser.add_argument("--write", metavar="PATH", help="the TOML file to write")


def run(args) -> int:
    from hexapod.errors import InputFileError
    from hexapod.scene.builtin import DEFAULT_SCENE, builtin_scenes, load_scene

    if args.name:
        from hexapod.scene.writer import write_scene

        scene = load_scene(args.name)
        if not args.write:
            raise InputFileError("give --write PATH to write the scene to a file")
        write_scene(scene, args.write, header=f"Built-in scene '{args.name}', written by "
                    f"'hexapod scenes {args.name} --write'.")
        print(f"wrote {args.write}")
        return 0
    scenes = builtin_scenes()
    if not scenes:
        print("no built-in scenes installed")
    for name in sorted(scenes):
        marker = " (default)" if name == DEFAULT_SCENE else ""
        print(f"{name}{marker}: {scenes[name].value}")
    return 0
