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


def positive(kind):
    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        if not (math.isfinite(value) and value > 0):
            raise argparse.ArgumentTypeError(f"must be positive, got {text}")
        return value
    return parse


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
