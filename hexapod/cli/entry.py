"""The first code the ``hexapod`` command runs: signals handled, then the command loaded.

Everything a user can cause ends with one line on stderr and a conventional status, from the
first line on: the signals are handled before anything else is imported, and a failure to load
the command (an interruption during the imports, too little memory for NumPy or CasADi, a broken
installation) is said in one line too. :mod:`hexapod.cli.app` does the rest.
"""

from __future__ import annotations

import os
import sys


def main(argv: list[str] | None = None) -> int:
    """Run the ``hexapod`` command with ``argv`` (default: the process's arguments); the exit
    status: 0 done, 1 an error of the input or the run, 2 a wrong command line, 3 an internal
    error, 130/143 interrupted by SIGINT/SIGTERM."""
    from hexapod._support import signals

    restore = signals.handle_signals()
    try:
        try:
            signals.deliver_signals()  # one that came while the handlers were installed: here
            app = _load()
        except BaseException as error:
            # an interruption, or another error an import made of one (see _interrupted)
            if _interrupted(error):
                print(signals.interruption(), file=sys.stderr)
                status = signals.exit_status()
            elif isinstance(error, (MemoryError, ImportError, OSError)):
                print(f"hexapod: error: cannot start: {type(error).__name__}: {error} (too "
                      "little memory, e.g. under 'ulimit -v', or a broken installation)",
                      file=sys.stderr)
                return 1
            else:
                raise
        else:
            try:
                status = app.main(argv)
            except KeyboardInterrupt:  # a signal after the command's own handling of one
                status = signals.exit_status()
    finally:
        if argv is None:  # the process itself: its work is done, a late signal changes nothing
            _ignore_late_signals(signals)
        else:
            restore()
    if argv is None and signals.received() is not None:
        # The process itself: end it with the status now. CPython would end a process whose
        # interruption went through its parser (a module compiled on import) by the signal
        # itself (status -2 to a caller) whatever status is returned.
        for stream in (sys.stdout, sys.stderr):
            stream.flush()
        os._exit(status)
    return status


def _load():
    """The command's module, imported (most of the start-up: NumPy, SciPy, CasADi)."""
    from hexapod.cli import app

    return app


def _interrupted(error: BaseException) -> bool:
    """Whether ``error`` is an interruption or was caused by one. Python wraps a
    ``KeyboardInterrupt`` raised while a class is being created in a ``RuntimeError`` ("Error
    calling __set_name__", seen with SIGINT during the standard library's ``ipaddress``
    import)."""
    seen = set()
    while error is not None and id(error) not in seen:
        if isinstance(error, KeyboardInterrupt):
            return True
        seen.add(id(error))
        error = error.__cause__ or error.__context__
    return False


def _ignore_late_signals(signals) -> None:
    """Ignore SIGINT and SIGTERM from now on, even when one arrives while the handlers are
    being replaced (its handler raises then: the replacement is done again, and the signal
    is remembered for the exit status)."""
    while True:
        try:
            signals.ignore_signals()
            return
        except KeyboardInterrupt:
            continue
