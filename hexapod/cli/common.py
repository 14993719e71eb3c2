"""What the commands share: argument types, the SCENE positional, progress lines on stderr and
JSON output.

Nothing here imports NumPy (nor anything that does), so that ``hexapod --help`` stays quick and
:func:`hexapod.cli.app.main` can limit the BLAS threads before NumPy is loaded.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys

from hexapod.catalog import MAX_FACES, POLICIES
from hexapod.scene.builtin import DEFAULT_SCENE

# ------------------------------------------------------------------ arguments


#: The largest time, duration or step (s) an option takes. At |t| = 1e9 s (32 years) consecutive
#: floating-point numbers are 1.2e-7 s apart, so a start plus a duration stays representable and
#: steps down to a microsecond still advance the time by several units of the last place; no
#: simulation or report of a legged robot spans decades.
MAX_TIME = 1e9
#: The largest count an option takes (samples, every N-th state): far beyond any memory, so the
#: jobs' own weighing (hexapod._support.limits) says what is too much; this only keeps the
#: arithmetic on counts in floating point.
MAX_COUNT = 10**15
#: The largest number of worker processes of a local cluster.
MAX_WORKERS = 1024


def _number(kind, accept, condition: str):
    """An argparse type: ``kind(text)``, finite and passing ``accept``, else the message
    "must be <condition>"."""
    def parse(text: str):
        try:
            value = kind(text)
        except (ValueError, OverflowError):
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        if not (math.isfinite(value) and accept(value)):
            raise argparse.ArgumentTypeError(f"must be {condition}, got {text}")
        return value
    return parse


def positive(kind):
    """An argparse type: a finite positive ``kind`` (int or float)."""
    return _number(kind, lambda value: value > 0, "positive")


def non_negative(kind):
    """An argparse type: a finite ``kind`` (int or float), zero or positive."""
    return _number(kind, lambda value: value >= 0, "zero or positive")


#: An instant in s (``--t``, ``--start``): finite, within MAX_TIME of zero.
time_value = _number(float, lambda value: abs(value) <= MAX_TIME,
                     f"a time between -{MAX_TIME:.0e} and {MAX_TIME:.0e} s".replace("e+0", "e"))
#: A length of time in s (``--t-end``, ``--duration``, ``--step``, ``--cpu-budget``).
seconds = _number(float, lambda value: 0 < value <= MAX_TIME,
                  f"positive and at most {MAX_TIME:.0e} s".replace("e+0", "e"))
#: A relative tolerance: a fraction, strictly between 0 and 1.
relative_tolerance = _number(float, lambda value: 0 < value < 1,
                             "positive and below 1 (e.g. 1e-6)")


def _increasing(times, where: str = ""):
    """``times`` (finite numbers) unchanged when they increase, else a ValueError."""
    for k in range(1, len(times)):
        if not times[k] > times[k - 1]:
            raise ValueError(f"the times must increase: {times[k]:g} after {times[k - 1]:g}"
                             + where)
    return times


def _time(text: str, where: str = "") -> float:
    try:
        value = float(text)
    except (ValueError, OverflowError):
        raise ValueError(f"not a number: {text.strip()!r}{where}") from None
    if not math.isfinite(value):
        raise ValueError(f"the times must be finite, got {text.strip()}{where}")
    return value


class TimesFile(str):
    """The path of a file of output times, one a line (``--t-eval @FILE``), read by
    :func:`read_times` once the run's limits are known."""


def output_times(text: str):
    """An argparse type: output times in s, ``T0,T1,...`` (finite, increasing: a tuple of
    floats) or ``@FILE`` (a :class:`TimesFile`, read later). Whether they lie within the run is
    checked once its duration is known."""
    if text.startswith("@"):
        if not text[1:].strip():
            raise argparse.ArgumentTypeError("@FILE: name a file of times, one a line")
        return TimesFile(text[1:])
    try:
        times = tuple(_time(part) for part in text.split(","))
        return _increasing(times)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def read_times(path: str, limit: int):
    """The output times of a file, one a line (blank lines and ``#`` comments skipped): an
    ``array('d')`` of at most ``limit`` finite, increasing times; a ValueError saying what is
    wrong (and where), or that the file cannot be read."""
    import io
    from array import array

    from hexapod._support.files import open_input
    from hexapod.errors import InputFileError

    times = array("d")
    try:
        with io.TextIOWrapper(open_input(path, "file of times"), encoding="utf-8") as lines:
            for number, line in enumerate(lines, 1):
                text = line.split("#", 1)[0].strip()
                if not text:
                    continue
                where = f" (line {number} of {path})"
                times.append(_time(text, where))
                if len(times) > 1 and not times[-1] > times[-2]:
                    _increasing(times[-2:], where)
                if len(times) > limit:
                    raise ValueError(f"{path} holds more than {limit:,} times, the limit of "
                                     "steps (--max-steps)")
    except InputFileError as error:
        raise ValueError(str(error)) from None
    except (OSError, UnicodeDecodeError) as error:
        raise ValueError(f"cannot read {path}: {getattr(error, 'strerror', None) or error}") \
            from None
    if not times:
        raise ValueError(f"{path} holds no time (write one time in s a line)")
    return times


def at_least(smallest: int, largest: int = MAX_COUNT):
    """An argparse type: a whole number from ``smallest`` to ``largest``, written ``5000`` or
    ``1e7``."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            try:
                number = float(text)
            except ValueError:
                raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
            if not (math.isfinite(number) and number == int(number)):
                raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
            value = int(number)
        if value < smallest:
            raise argparse.ArgumentTypeError(f"must be at least {smallest}, got {text}")
        if value > largest:
            raise argparse.ArgumentTypeError(f"must be at most {short(largest)}, got {text}")
        return value
    return parse


def memory_size(text: str) -> int:
    """An argparse type: a memory size in bytes, written ``16G``, ``512M``."""
    from hexapod._support.limits import parse_size

    try:
        return parse_size(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def limit_arguments(parser: argparse.ArgumentParser, steps: bool = False) -> None:
    """``--max-memory`` (and with ``steps``, ``--max-steps``): the limits a job is weighed
    against before it starts (hexapod._support.limits)."""
    group = parser.add_argument_group(
        "limits", "a job estimated to need more is refused before it starts")
    group.add_argument("--max-memory", type=memory_size, metavar="SIZE",
                       help="memory the job may use, e.g. 16G or 512M (default: "
                       "HEXAPOD_MAX_MEMORY, else half the machine's memory, at most 8G)")
    if steps:
        group.add_argument("--max-steps", type=at_least(1), metavar="N",
                           help="steps the run may take (default: HEXAPOD_MAX_STEPS, else "
                           "1e7)")


#: Bytes per number of a sample (positions, velocities, accelerations, law values and their
#: rates, multipliers, joint wrenches, ground forces) that inverse dynamics and its report hold
#: until the files are written: the peak memory of 'hexapod report' grows by 27 to 38 bytes per
#: number and sample (front-leg, hexapod and hexapod-held, 1000 to 80,000 samples).
INVERSE_BYTES_PER_NUMBER = 32


def check_inverse_memory(model, samples: int, limit: int | None, lower: str) -> None:
    """Refuse inverse dynamics of ``samples`` samples of ``model`` whose memory would pass the
    limit (``--max-memory``, else ``HEXAPOD_MAX_MEMORY``, else the default), before any
    work; ``lower`` says how to ask for fewer samples."""
    from hexapod._support.limits import check_memory

    numbers = (model.n_q + 2 * model.n_v + 3 * model.n_w + model.n_c + 7 * len(model.joints)
               + 4 * len(model.contacts))
    check_memory(float(samples) * numbers * INVERSE_BYTES_PER_NUMBER,
                 f"inverse dynamics of {samples} samples of '{model.name}'", lower, limit)


def pyramid_faces(text: str) -> int:
    """Faces of the friction pyramid: 0 (the exact cone) or at least 3."""
    value = at_least(0, MAX_FACES)(text)
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
    parser.add_argument("--t", type=time_value, default=0.0,
                        help="time in s, within 1e9 s of 0 (default 0)")
    parser.add_argument("--json", action="store_true", help=json_help)


def window_arguments(parser: argparse.ArgumentParser, samples: int | None = None) -> None:
    """``--start``, ``--duration``, ``--samples``: the inverse dynamics' window (``report``,
    ``sensitivity``); ``samples`` the default count (None: the command decides, 501)."""
    parser.add_argument("--start", type=time_value, default=0.0, metavar="S",
                        help="first time in s (default 0)")
    parser.add_argument("--duration", type=seconds, metavar="S",
                        help="length of the window in s (default: one cycle of the scene's "
                        "periodic laws, e.g. the gait's stride, or 1 s)")
    parser.add_argument("--samples", type=at_least(2), default=samples,
                        help="samples over the window, ends included (default 501)")


def inverse_arguments(parser: argparse.ArgumentParser, method_help: str) -> None:
    """``--frame`` and ``--method`` of the inverse dynamics (``inverse`` and ``report``)."""
    parser.add_argument("--frame", choices=("joint", "world"), default="joint",
                        help="axes of the wrench components (default: the child's joint frame)")
    parser.add_argument("--method", choices=("auto", "tree", "phase", "saddle"), default="auto",
                        help=method_help)
    compile_argument(parser, "the inverse dynamics")


def compile_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """``--compile yes|no``: ``what`` evaluated as compiled C code or by CasADi's virtual
    machine (the execution setting the command runs in)."""
    parser.add_argument("--compile", choices=("yes", "no"), default="no",
                        help=f"evaluate {what} as C code compiled by the system's C "
                        "compiler (kept in the cache, so later runs of the model load it) "
                        "rather than by CasADi's virtual machine (default no: the same numbers; "
                        "compiled code pays on long runs, see docs/cache.md)")


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


def base_argument(parser: argparse.ArgumentParser) -> None:
    """``--base``: how a URDF model's root link stands."""
    parser.add_argument("--base", choices=("auto", "free", "fixed"), default="auto",
                        help="a URDF model's root link: free (a floating base, e.g. a legged "
                        "robot's trunk), fixed (welded to the ground), or auto (the default: "
                        "free when it has mass, else the ground)")


def scene_of(args, name: str):
    """The scene ``name`` (a file or a built-in scene) with the command's ``--base`` and ground
    options applied."""
    from hexapod.scene.builtin import load_scene

    return apply_ground_options(load_scene(name, base=args.base), args)


def apply_ground_options(scene, args):
    """``scene`` with its ground-force settings (``scene.ground``) replaced by a copy that
    takes the ground options given in ``args``; a :class:`~hexapod.errors.HexapodError` when
    options are given for a scene without foot contacts."""
    import dataclasses

    given = {name: getattr(args, name) for name in GROUND_OPTIONS
             if getattr(args, name, None) is not None}
    if not given:
        return scene
    from hexapod.scene.joints import Contact

    if not any(isinstance(joint, Contact) for joint in scene.joints.values()):
        from hexapod.errors import HexapodError

        options = ", ".join("--" + name.replace("_", "-") for name in given)
        raise HexapodError(f"{options}: scene '{scene.name}' has no foot contacts, so no ground "
                           "forces to share (these options are for walking scenes, e.g. "
                           "'hexapod')")
    scene.ground = dataclasses.replace(scene.ground, **given)
    return scene


# ------------------------------------------------------------------ progress on stderr


def show_progress() -> bool:
    """Whether the progress lines are drawn on stderr: on a terminal, and wherever
    ``HEXAPOD_PROGRESS=1`` asks for them (a log, a program that watches the run)."""
    return sys.stderr.isatty() or os.environ.get("HEXAPOD_PROGRESS", "0") not in ("", "0")


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
