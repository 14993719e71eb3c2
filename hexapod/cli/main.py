"""The ``hexapod`` command: the parser of every command, and the one way errors end.

Every error a user can cause ends with one message on stderr and a non-zero exit, never a
traceback (set ``HEXAPOD_DEBUG=1`` to see one for an internal error). Each command is a module of
this folder with ``HELP``, ``DESCRIPTION``, ``add_arguments(parser)`` and ``run(args)``; the
modules import NumPy, CasADi and the engine only in ``run``, so that ``--help`` and a short job do
not pay for the others' imports.
"""

from __future__ import annotations

import argparse
import os
import sys
import warnings

from hexapod._version import __version__
from hexapod.cli import (
    bench,
    check,
    dynamics,
    export,
    info,
    inverse,
    report,
    scenes,
    simulate,
    sweep,
    validate,
)
from hexapod.errors import HexapodError

#: The commands, in the order ``hexapod --help`` lists them; each is named by its module.
COMMANDS = (dynamics, info, inverse, report, simulate, sweep, check, export, bench, validate,
            scenes)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="hexapod",
        description="Constrained multibody dynamics in absolute coordinates for legged robots.")
    parser.add_argument("--version", action="version", version=f"hexapod {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for command in COMMANDS:
        name = command.__name__.rpartition(".")[2]
        p = sub.add_parser(name, help=command.HELP, description=command.DESCRIPTION)
        command.add_arguments(p)
        p.set_defaults(run=command.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    import signal
    import threading

    # One BLAS thread, set before anything imports NumPy: the matrices of a mechanism are small,
    # and OpenBLAS threads cost more in start-up and synchronisation than they save. The library
    # itself changes no process state; the test session sets the same (tests/conftest.py).
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    # SIGTERM (kill, a CI timeout) interrupts like Ctrl-C, so that a file being written is
    # removed rather than left behind half-written
    in_main_thread = threading.current_thread() is threading.main_thread()
    if in_main_thread:
        terminate = signal.signal(signal.SIGTERM, signal.default_int_handler)
    try:
        args = build_parser().parse_args(argv)
        with warnings.catch_warnings(record=True) as caught:
            try:
                return args.run(args)
            finally:
                for message in dict.fromkeys(str(w.message) for w in caught):
                    print(f"hexapod: warning: {message}", file=sys.stderr)
    except HexapodError as error:
        print(f"hexapod: error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("hexapod: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into a reader that stopped (e.g. head): not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except Exception as error:  # an internal error: still one line unless debugging
        if os.environ.get("HEXAPOD_DEBUG"):
            raise
        print(f"hexapod: internal error: {type(error).__name__}: {error} "
              "(set HEXAPOD_DEBUG=1 for the traceback)", file=sys.stderr)
        return 3
    finally:
        if in_main_thread:
            signal.signal(signal.SIGTERM, terminate)
