"""CasADi Functions built once and kept in the cache on disk (:mod:`hexapod._support.cache`):
compiled to C as shared libraries, or serialized as they are.

One small API for every compiled kernel::

    function = compiled(key, build)      # a shared library: compiled in the first process only
    function = serialized(key, build)    # the Function itself: its graph built once
    function = find_compiled(key)        # the library when one is cached, else None

The cache is the execution setting's (:mod:`hexapod._support.execution`): without one, a
library is compiled in a temporary folder, loaded and the folder removed, and nothing is kept.
``key`` says everything the Function depends on beyond hexapod's own sources (which every key
includes): typically the model's content hash and the kernel's name and options, e.g.
``f"{model.digest}/tree-inverse"``. ``build()`` makes the Function (an ``SX`` or ``MX``
Function), and is called only when the cache has none. A compiled library's key also holds the
CasADi version, the compiler and its flags, and the machine.

Compiling: CasADi generates C (``CodeGenerator``), the system's C compiler (``gcc``, else
``cc``) makes a shared library of it, and ``casadi.external`` loads it. Without a compiler, or
with ``HEXAPOD_NO_JIT=1``, :func:`compiled` returns the interpreted Function; a compiler that
fails is said in a :class:`CompilerWarning` and the interpreted Function is used.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import sys
import warnings
from collections.abc import Callable
from pathlib import Path

import casadi as ca

from hexapod._support import cache
from hexapod._support.files import write_atomically
from hexapod.errors import HexapodError

#: Flags of the C compiler: the tree-ordered inverse dynamics runs 5 to 7 times faster than in
#: CasADi's interpreter.
COMPILER_FLAGS = ("-O2",)
#: The files of a compiled entry: the library and the name of the Function it holds.
LIBRARY, NAME = "library" + (".dll" if sys.platform == "win32" else
                             ".dylib" if sys.platform == "darwin" else ".so"), "name.txt"
#: The file of a serialized entry.
SERIALIZED = "function.casadi"


class CompilerWarning(UserWarning):
    """The C compiler failed: the interpreted Function is used (same numbers, slower)."""


def compiler() -> str | None:
    """The C compiler used (a path), or None: none found, or ``HEXAPOD_NO_JIT`` set."""
    if os.environ.get("HEXAPOD_NO_JIT"):
        return None
    return shutil.which("gcc") or shutil.which("cc")


def compiled_key(key: str, command: str) -> str:
    """The cache key of ``key``'s library, compiled by ``command`` (a compiler's path) with
    :data:`COMPILER_FLAGS`."""
    return cache.key("compiled", key, f"casadi {ca.__version__}", command,
                     " ".join(COMPILER_FLAGS),
                     sys.platform, _machine())


def _machine() -> str:
    """The processor's architecture (``os.uname``: without loading ``platform``, 1 ms)."""
    if hasattr(os, "uname"):
        return os.uname().machine
    import platform

    return platform.machine()


def serialized_key(key: str) -> str:
    """The cache key of ``key``'s serialized Function."""
    return cache.key("serialized", key, f"casadi {ca.__version__}")


def find_compiled(key: str | None) -> ca.Function | None:
    """The library of ``key`` when the cache holds one (loaded), else None."""
    command = compiler()
    if command is None or key is None or cache.folder() is None:  # no key: it stats the sources
        return None
    entry_key = compiled_key(key, command)
    found = cache.load(entry_key)
    if found is None:
        return None
    path, files = found
    try:
        return ca.external(files[NAME].decode("utf-8").strip(), str(path / LIBRARY))
    except (KeyError, UnicodeDecodeError, RuntimeError):  # not a library CasADi can load
        cache.discard(entry_key)
        return None


def compiled(key: str | None, build: Callable[[], ca.Function], *,
             what: str = "") -> ca.Function:
    """The Function ``build()`` makes, compiled to C with :data:`COMPILER_FLAGS`:
    loaded from the cache when it holds the library of ``key``, else built, compiled and stored
    there (``what`` says what it is, for ``hexapod cache info``);
    with ``key=None``, compiled and not stored. The interpreted Function when there is no
    compiler."""
    found = find_compiled(key)
    if found is not None:
        return found
    function = build()
    command = compiler()
    if command is None:
        return function
    stored = key is not None and cache.folder() is not None
    entry_key = compiled_key(key, command) if stored else None
    said = f"{what or function.name()}, compiled {' '.join(COMPILER_FLAGS)}"
    try:
        with cache.writing(entry_key, said) as folder:
            library = _compile(function, folder, command)
            # loaded before the folder is published or removed: the library stays mapped
            return ca.external(function.name(), str(library))
    except (CompileError, HexapodError) as error:  # nothing was stored
        warnings.warn(str(error), CompilerWarning, stacklevel=2)
        return function


class CompileError(Exception):
    """The C compiler failed (its last lines of output in the message)."""


def _compile(function: ca.Function, folder: Path, command: str) -> Path:
    """Generate ``function``'s C code in ``folder`` and compile it to a shared library there;
    the source is removed (only the library is kept)."""
    generator = ca.CodeGenerator("source.c", {"with_header": False})
    generator.add(function)
    try:
        generator.generate(str(folder) + os.sep)
    except RuntimeError as error:  # the folder cannot be written (a full disk)
        raise CompileError(f"cannot write the C code of {function.name()} ({error})") from None
    source, library = folder / "source.c", folder / LIBRARY
    status, said = _run_compiler([command, *COMPILER_FLAGS, "-shared", "-fPIC", str(source), "-o",
                                  str(library)])
    source.unlink()
    if status != 0 or not library.is_file():
        said = " / ".join(said.strip().splitlines()[-3:])
        raise CompileError(f"{command} could not compile {function.name()} (status {status}: "
                           f"{said}): CasADi's interpreter is used instead (same numbers, "
                           "slower)")
    write_atomically(folder / NAME, function.name(), durable=False)
    return library


def _run_compiler(arguments: list[str]) -> tuple[int, str]:
    """Run the compiler; its status and what it said. A child process in a process group of its
    own, not ``system()`` (which would ignore an interruption): an interruption or any other
    exception here ends the whole group (the driver and the compiler proper it starts, which
    would go on alone otherwise) and is raised again."""
    import signal
    import subprocess  # only to compile: 2 ms of every run's start otherwise

    group = hasattr(os, "killpg")
    process = subprocess.Popen(arguments, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True, errors="replace", start_new_session=group)
    try:
        said, _ = process.communicate()
    except BaseException:
        if group:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(process.pid, signal.SIGKILL)
        else:  # pragma: no cover - not a POSIX system
            process.kill()
        process.wait()
        raise
    return process.returncode, said


def serialized(key: str | None, build: Callable[[], ca.Function], *,
               what: str = "") -> ca.Function:
    """The Function ``build()`` makes, loaded from the cache when it holds the serialized
    Function of ``key`` (no graph to build), else built and stored there; with ``key=None``,
    ``build()`` alone."""
    if key is None or cache.folder() is None:
        return build()
    entry_key = serialized_key(key)
    found = cache.load(entry_key)
    if found is not None:
        try:
            return ca.Function.deserialize(found[1][SERIALIZED].decode("ascii"))
        except (KeyError, UnicodeDecodeError, RuntimeError):
            cache.discard(entry_key)
    function = build()
    cache.keep(entry_key, f"{what or function.name()}, serialized",
               {SERIALIZED: function.serialize()}, stacklevel=2)
    return function
