"""What the commands share: argument types, the SCENE positional, progress lines on stderr and
JSON output.

Nothing here imports NumPy (nor anything that does), so that ``hexapod --help`` stays quick and
:func:`hexapod.cli.main.main` can limit the BLAS threads before NumPy is loaded.
"""

from __future__ import annotations

import argparse
import json
import math
import sys

from hexapod.scene.builtin import DEFAULT_SCENE

# ------------------------------------------------------------------ arguments


def _number(kind, accept, condition: str):
    """An argparse type: ``kind(text)``, finite and passing ``accept``, else the message
    "must be <condition>"."""
    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        if not (math.isfinite(value) and accept(value)):
            raise argparse.ArgumentTypeError(f"must be {condition}, got {text}")
        return value
    return parse


def positive(kind):
    """An argparse type: a finite positive ``kind`` (int or float)."""
    return _number(kind, lambda value: value > 0, "positive")


def at_least(smallest: int):
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
        if value < smallest:
            raise argparse.ArgumentTypeError(f"must be at least {smallest}, got {value}")
        return value
    return parse


def non_negative(kind):
    """An argparse type: a finite ``kind`` (int or float), zero or positive."""
    return _number(kind, lambda value: value >= 0, "zero or positive")


def pyramid_faces(text: str) -> int:
    """Faces of the friction pyramid: 0 (the exact cone) or at least 3."""
    value = at_least(0)(text)
    if 0 < value < 3:
        raise argparse.ArgumentTypeError(f"must be 0 (the exact cone) or at least 3, got {value}")
    return value


def short(value: float) -> str:
    """A number as a user writes it: 1e-06 as 1e-6."""
    mantissa, e, exponent = f"{value:g}".partition("e")
    return f"{mantissa}e{int(exponent)}" if e else mantissa


def scene_positional(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", nargs="?", default=DEFAULT_SCENE,
                        help="a TOML scene file or a built-in scene name (default: "
                        f"{DEFAULT_SCENE})")


def scene_arguments(parser: argparse.ArgumentParser, json_help: str) -> None:
    scene_positional(parser)
    parser.add_argument("--t", type=float, default=0.0, help="time in s (default 0)")
    parser.add_argument("--json", action="store_true", help=json_help)


def inverse_arguments(parser: argparse.ArgumentParser, method_help: str) -> None:
    """``--frame`` and ``--method`` of the inverse dynamics (``inverse`` and ``report``)."""
    parser.add_argument("--frame", choices=("joint", "world"), default="joint",
                        help="axes of the wrench components (default: the child's joint frame)")
    parser.add_argument("--method", choices=("auto", "tree", "saddle"), default="auto",
                        help=method_help)


#: The ground-force policies (hexapod.scene.contacts.POLICIES, not imported: it loads NumPy).
POLICIES = ("min-wrench", "min-effort", "friction")
#: The ground options, each named as the GroundForces field it sets.
GROUND_OPTIONS = ("policy", "mu", "faces", "min_normal")


def ground_arguments(parser: argparse.ArgumentParser) -> None:
    """``--policy``, ``--mu``, ``--faces``, ``--min-normal``: the scene's ground-force settings
    overridden (scenes with foot contacts)."""
    group = parser.add_argument_group(
        "ground forces", "override the scene's ground-force settings (scenes whose feet touch "
        "the ground by contacts, e.g. the built-in 'hexapod')")
    group.add_argument("--policy", choices=POLICIES,
                       help="how the forces are shared among the feet in stance: least joint "
                       "wrenches, least actuator efforts, or least efforts with every foot "
                       "inside its friction cone (default: the scene's)")
    group.add_argument("--mu", type=positive(float), metavar="MU",
                       help="friction coefficient: the friction policy's cone and the reported "
                       "friction ratio |F_t| / (mu F_n) (default: the scene's)")
    group.add_argument("--faces", type=pyramid_faces, metavar="N",
                       help="friction policy: the cone as a pyramid of N faces inscribed in it, "
                       "0 for the exact cone (default: the scene's)")
    group.add_argument("--min-normal", type=non_negative(float), metavar="N",
                       help="friction policy: least normal force of a foot in full stance, in "
                       "newtons (default: the scene's)")


def apply_ground_options(scene, args):
    """``scene`` with its ground-force settings (``scene.ground``) replaced by a copy that
    takes the ground options given in ``args``; a :class:`~hexapod.errors.HexapodError` when
    options are given for a scene without foot contacts."""
    import dataclasses

    given = {name: getattr(args, name) for name in GROUND_OPTIONS
             if getattr(args, name, None) is not None}
    if not given:
        return scene
    if not any(joint.kind == "contact" for joint in scene.joints.values()):
        from hexapod.errors import HexapodError

        options = ", ".join("--" + name.replace("_", "-") for name in given)
        raise HexapodError(f"{options}: scene '{scene.name}' has no foot contacts, so no ground "
                           "forces to share (these options are for walking scenes, e.g. "
                           "'hexapod')")
    scene.ground = dataclasses.replace(scene.ground, **given)
    return scene


# ------------------------------------------------------------------ progress on stderr


def time_progress(method: str, t0: float):
    """A progress bar on stderr, redrawn at most ten times a second."""
    import time

    last = [0.0]

    def report(t: float, t_end: float) -> None:
        now = time.perf_counter()
        if now - last[0] > 0.1 or t >= t_end:
            last[0] = now
            done = min(max((t - t0) / (t_end - t0), 0.0), 1.0)
            bar = "#" * int(30 * done) + "." * (30 - int(30 * done))
            print(f"\r{method} [{bar}] {100 * done:3.0f} %  t = {t:.4g} s", end="",
                  file=sys.stderr, flush=True)
    return report


def sample_progress(label: str):
    def report(done: int, total: int) -> None:
        if done == total or done % max(1, total // 100) == 0:
            print(f"\r{label}: {done}/{total} samples", end="", file=sys.stderr, flush=True)
    return report


# ------------------------------------------------------------------ output


def jsonable(value):
    """Plain JSON: non-finite numbers (e.g. the smallest singular value of a scene without
    constraints, infinite) written as null."""
    if isinstance(value, dict):
        return {k: jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def emit(report: dict, as_json: bool, formatter) -> None:
    if as_json:
        json.dump(jsonable(report), sys.stdout, indent=2, allow_nan=False)
        print()
    else:
        print(formatter(report))
