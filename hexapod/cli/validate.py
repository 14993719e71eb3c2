"""``hexapod validate``: check a scene and list every problem."""

from __future__ import annotations

HELP = "check a scene and list every problem"
DESCRIPTION = "Read SCENE and report every problem found, or that it is valid."


def add_arguments(parser) -> None:
    parser.add_argument("scene", help="a TOML scene file or a built-in scene name")


def _count(n: int, noun: str) -> str:
    plural = "bodies" if noun == "body" else noun + "s"
    return f"{n} {noun if n == 1 else plural}"


def run(args) -> int:
    from hexapod._support.limits import check_model_size
    from hexapod.scene.builtin import load_scene

    scene = load_scene(args.scene)
    # refused as every command that assembles it refuses it
    check_model_size(len(scene.bodies), len(scene.joints), f"scene '{scene.name}' "
                     f"({args.scene})", sum(j.kind == "contact" for j in scene.joints.values()))
    scene.validate()
    counts = ", ".join(_count(len(items), noun) for items, noun in (
        (scene.bodies, "body"), (scene.joints, "joint"), (scene.drivers, "driver"),
        (scene.forces, "force element")))
    print(f"{args.scene}: scene '{scene.name}' is valid ({counts})")
    return 0
