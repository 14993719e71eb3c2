"""How the library evaluates its CasADi Functions, and whether it keeps anything on disk: one
setting, chosen by the caller, never by the algorithms.

========================  ==================================================================
``compiled``              evaluate the inverse dynamics' Functions as C code compiled by the
                          system's C compiler (``gcc`` or ``cc``), else (the default) by
                          CasADi's virtual machine. The same numbers either way, to round-off;
                          without a compiler the virtual machine is used
``cache``                 a folder where compiled libraries are kept between runs
                          (:mod:`hexapod._support.cache`);
                          ``None`` (the default): nothing is read from or written to disk
``cache_size``            the most the cache may hold, in bytes
========================  ==================================================================

A library call reads the setting of its context (:func:`current`); a caller changes it for a
block with :func:`executing`, e.g. ::

    with hexapod.executing(compiled=True, cache="~/.cache/hexapod"):
        result = hexapod.inverse_dynamics(model, times)

The setting is a context variable: threads and asynchronous tasks each see their own, and a
block changes nothing outside itself. The command line turns the cache on for its own runs
(``hexapod --help`` says how).
"""

from __future__ import annotations

import contextlib
import contextvars
import os
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path

#: The default size limit of the cache (1 GiB).
DEFAULT_CACHE_SIZE = 2**30


@dataclass(frozen=True)
class Execution:
    """How Functions are evaluated and where built code is kept.

    Attributes
    ----------
    compiled : bool
        Evaluate as compiled C code (True) or by CasADi's virtual machine (False, default).
    cache : pathlib.Path or None
        The cache folder, or None (default): nothing read from or written to disk.
    cache_size : int
        The most the cache may hold, in bytes (default 1 GiB).
    """

    compiled: bool = False
    cache: Path | None = None
    cache_size: int = DEFAULT_CACHE_SIZE

    def __post_init__(self):
        if self.cache is not None:
            object.__setattr__(self, "cache", Path(os.fspath(self.cache)).expanduser())
        if not (isinstance(self.cache_size, int) and self.cache_size > 0):
            raise ValueError(f"cache_size must be a positive number of bytes, got "
                             f"{self.cache_size!r}")


#: The setting of a context that was given none: interpreted, no cache.
DEFAULT = Execution()
_CURRENT: contextvars.ContextVar[Execution] = contextvars.ContextVar("hexapod_execution",
                                                                     default=DEFAULT)


def current() -> Execution:
    """The setting in force in this context."""
    return _CURRENT.get()


@contextlib.contextmanager
def executing(execution: Execution | None = None,
              **changes: bool | str | os.PathLike | int | None) -> Iterator[Execution]:
    """Run a block with ``execution`` (default: the current setting) changed by ``changes``
    (``compiled``, ``cache``, ``cache_size``); the setting before is restored after it.

    Parameters
    ----------
    execution : Execution, optional
        The setting to start from (default: the current one).
    **changes
        Fields of :class:`Execution` to change: ``compiled`` (bool), ``cache`` (a folder, or
        None), ``cache_size`` (bytes).

    Yields
    ------
    Execution
        The setting in force in the block.

    Raises
    ------
    TypeError
        A change that is not a field of :class:`Execution`.
    """
    setting = replace(execution if execution is not None else current(), **changes)
    token = _CURRENT.set(setting)
    try:
        yield setting
    finally:
        _CURRENT.reset(token)
