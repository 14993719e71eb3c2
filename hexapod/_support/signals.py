"""How a run ends on a signal: SIGINT and SIGTERM interrupt it, and are remembered.

The command line installs :func:`handle_signals` before anything else. Both signals then raise
``KeyboardInterrupt`` in the main thread, so that whatever is being written is removed (or, for
a simulation, what was computed is written, marked interrupted), and the process ends with the
conventional status 128 + the signal's number (130, 143). The signal is also remembered: a
library may swallow the ``KeyboardInterrupt`` (CasADi turns an interrupt inside its own code into
an error of its own), and the command line still ends as interrupted.

A C compiler started by CasADi runs through ``system()``, which ignores SIGINT in the calling
process: a signal sent to this process alone would be lost. :func:`deferred` blocks the signals
around such calls instead, so that one arriving meanwhile is delivered as soon as the call
returns. Outside the command line (the library used from Python) nothing here changes any
process state.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading

#: The signals that end a run.
ENDING = (signal.SIGINT, signal.SIGTERM)

_received: list[int] = []
#: Whether the handlers raise (from :func:`deliver_signals` on); before, they only remember.
_armed: list[bool] = []


def _handler(number, frame) -> None:
    _received.append(number)
    if _armed:
        raise KeyboardInterrupt


def handle_signals():
    """SIGINT and SIGTERM raise ``KeyboardInterrupt`` and are remembered (main thread only);
    returns a function that puts back the handlers found (and forgets the signal). Until
    :func:`deliver_signals`, called first thing inside the caller's ``try``, a signal is only
    remembered: one right after the start (a shell's, between the two installations) once
    raised inside this function, outside any handling of it. (Blocking the signals would not
    do: in a process with threads the kernel hands a signal to a thread that does not block
    it.)"""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    _received.clear()
    _armed.clear()
    earlier = {number: signal.signal(number, _handler) for number in ENDING}
    hook = sys.unraisablehook
    sys.unraisablehook = _quiet_interruptions(hook)

    def restore() -> None:  # and forget the signal: a later call in this process is new
        for number, handler in earlier.items():
            signal.signal(number, handler)
        sys.unraisablehook = hook
        _received.clear()
        _armed.clear()
    return restore


def _quiet_interruptions(hook):
    """``hook`` (``sys.unraisablehook``) except for a ``KeyboardInterrupt``: a signal whose
    handler raised inside a callback or a finalizer (seen in importlib's module-lock callback
    during the imports), where Python can only print the exception and go on. The signal is
    remembered all the same, and the command ends as interrupted: the printed traceback was
    the only trace it left."""
    def quiet(unraisable) -> None:
        if not issubclass(unraisable.exc_type, KeyboardInterrupt):
            hook(unraisable)
    return quiet


def deliver_signals() -> None:
    """From now on the signals raise; one that came since :func:`handle_signals` raises
    ``KeyboardInterrupt`` here."""
    if not _armed:
        _armed.append(True)
        if _received:
            raise KeyboardInterrupt


def ignore_signals() -> None:
    """SIGINT and SIGTERM ignored from now on: for a process whose work is done and whose
    status is set, so that a signal arriving while it exits cannot change that status."""
    if threading.current_thread() is threading.main_thread():
        for number in ENDING:
            signal.signal(number, signal.SIG_IGN)


def received() -> int | None:
    """The first ending signal received since :func:`handle_signals`, or None."""
    return _received[0] if _received else None


def exit_status() -> int:
    """The conventional status of a process ended by the signal received (130 for SIGINT, 143
    for SIGTERM); 130 when the interruption came otherwise (a ``KeyboardInterrupt``)."""
    number = received()
    return 128 + (number if number is not None else signal.SIGINT)


def interruption() -> str:
    """The line that ends an interrupted command: ``hexapod: interrupted (SIGTERM)``, without
    the name when the interruption came otherwise (a ``KeyboardInterrupt`` raised in code)."""
    number = received()
    return ("hexapod: interrupted" if number is None
            else f"hexapod: interrupted ({signal.Signals(number).name})")


@contextlib.contextmanager
def deferred():
    """Hold SIGINT and SIGTERM back while the block runs (a call into C code that cannot be
    interrupted safely, e.g. a compiler); one that arrived is delivered when it ends."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    blocked = signal.pthread_sigmask(signal.SIG_BLOCK, ENDING)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, blocked)
