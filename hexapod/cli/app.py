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
    cache,
    check,
    dynamics,
    export,
    info,
    inverse,
    optimize,
    report,
    scenes,
    sensitivity,
    simulate,
    sweep,
    validate,
)
from hexapod.errors import HexapodError

#: The commands, in the order ``hexapod --help`` lists them; each is named by its module.
COMMANDS = (dynamics, info, inverse, report, sensitivity, optimize, simulate, sweep, check,
            export, bench, validate, scenes, cache)


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The parser of every command; given the arguments ``argv`` it will parse, only the
    command they name gets its arguments (the others' are not needed, and building them all
    costs 4 ms of every run)."""
    parser = argparse.ArgumentParser(
        prog="hexapod",
        description="Constrained multibody dynamics in absolute coordinates for legged robots.")
    parser.add_argument("--version", action="version", version=f"hexapod {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    names = [command.__name__.rpartition(".")[2] for command in COMMANDS]
    chosen = _command_named(argv, names)
    for name, command in zip(names, COMMANDS, strict=True):
        p = sub.add_parser(name, help=command.HELP, description=command.DESCRIPTION)
        if chosen is None or name == chosen:
            command.add_arguments(p)
        p.set_defaults(run=command.run)
    return parser


def _command_named(argv: list[str] | None, names: list[str]) -> str | None:
    """The command ``argv`` runs: its first argument when it names one (the options before it
    are the program's own: --help, --version), else None (every command's arguments built)."""
    if argv is None:
        return None
    first = next((a for a in argv if not a.startswith("-")), None)
    return first if first in names else None


def main(argv: list[str] | None = None) -> int:
    """Parse ``argv`` and run its command; every way it can end is one line on stderr and a
    status (see :func:`hexapod.cli.entry.main`, which handles the signals before this runs)."""
    from hexapod._support import signals

    # One BLAS thread, set before anything imports NumPy: the matrices of a mechanism are small,
    # and OpenBLAS threads cost more in start-up and synchronisation than they save. The library
    # itself changes no process state; the test session sets the same (tests/conftest.py).
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    try:
        args = build_parser(sys.argv[1:] if argv is None else argv).parse_args(argv)
        _check_address_space()
        status = _run(args)
    except HexapodError as error:
        print(f"hexapod: error: {error}", file=sys.stderr)
        status = 1
    except KeyboardInterrupt:
        status = None
    except MemoryError:
        print("hexapod: error: out of memory; ask for less (fewer samples, a shorter run, a "
              "smaller model) or run where there is more memory", file=sys.stderr)
        status = 1
    except ImportError as error:  # NumPy, CasADi... cannot load: too little memory, or broken
        last = (str(error).strip().splitlines() or [""])[-1]  # NumPy's is a page long
        print(f"hexapod: error: cannot load {error.name or 'a library'}: {last} (too little "
              "memory, e.g. under 'ulimit -v', or a broken installation)", file=sys.stderr)
        status = 1
    except BrokenPipeError:  # output piped into a reader that stopped (e.g. head): not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        status = 0
    except Exception as error:
        if signals.received() is not None:  # an interruption a library turned into an error
            status = None
        elif os.environ.get("HEXAPOD_DEBUG"):
            raise
        else:  # an internal error: still one line unless debugging
            print(f"hexapod: internal error: {type(error).__name__}: {error} "
                  "(set HEXAPOD_DEBUG=1 for the traceback)", file=sys.stderr)
            status = 3
    if status in (130, 143):  # the command said how it was interrupted (simulate)
        return signals.exit_status()
    # a signal a library swallowed (turned into an error of its own, or ignored) still ends the
    # run as interrupted
    if status is None or signals.received() is not None:
        print(signals.interruption(), file=sys.stderr)
        return signals.exit_status()
    return status


#: Address space the commands need to load NumPy, SciPy and CasADi (about 360 MiB measured for
#: a report with one BLAS thread), with a margin. Below it, OpenBLAS's start-up retries its
#: allocation forever rather than failing, so the limit is checked before anything is loaded.
ADDRESS_SPACE_NEEDED = 512 * 2**20


def _check_address_space() -> None:
    try:
        import resource
    except ImportError:  # not a POSIX system: no such limit
        return
    limit = resource.getrlimit(resource.RLIMIT_AS)[0]
    if limit != resource.RLIM_INFINITY and limit < ADDRESS_SPACE_NEEDED:
        raise HexapodError(f"the address-space limit (ulimit -v) is {limit / 2**20:.0f} MiB; "
                           f"hexapod needs at least {ADDRESS_SPACE_NEEDED / 2**20:.0f} MiB to "
                           "load NumPy, SciPy and CasADi: raise it")


def _run(args) -> int:
    """Run the command, its warnings said once each after it; a library that ends the process
    (``sys.exit``) ends the command with an error instead. The command runs with the cache on
    disk turned on (in the folder the environment names, see ``hexapod cache --help``), and
    compiled when it asks for it (``--compile yes``)."""
    from hexapod._support import cache
    from hexapod._support.execution import executing

    with warnings.catch_warnings(record=True) as caught, executing(
            compiled=getattr(args, "compile", "no") == "yes", **cache.configured()):
        try:
            return args.run(args)
        except SystemExit as ended:
            raise HexapodError(f"a library tried to end the process (exit status {ended.code!r})"
                               " during the command") from None
        finally:
            for message in dict.fromkeys(str(w.message) for w in caught):
                print(f"hexapod: warning: {message}", file=sys.stderr)
