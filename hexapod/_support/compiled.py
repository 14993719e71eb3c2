"""CasADi Functions compiled to C as shared libraries, kept in the cache on disk
(:mod:`hexapod._support.cache`).

One small API for every compiled kernel::

    function = compiled(key, build)      # a shared library: compiled in the first process only
    function = find_compiled(key)        # the library when one is cached, else None

Only libraries are kept, never a serialized Function: CasADi's deserializer loads whatever
library a serialized ``External`` names, so reading one back would run code from the cache
folder, for a saving of a few tens of milliseconds of graph building.

The cache is the execution setting's (:mod:`hexapod._support.execution`): without one, a
library is compiled in a temporary folder, loaded and the folder removed, and nothing is kept.
``key`` says everything the Function depends on beyond hexapod's own sources (which every key
includes): typically the model's content hash and the kernel's name and options, e.g.
``f"{model.digest}/tree-inverse"``. ``build()`` makes the Function (an ``SX`` or ``MX``
Function), and is called only when the cache has none. A compiled library's key also holds the
CasADi version, the compiler and its flags, and the machine (with the processor's features
where the code is compiled for them: :func:`compiler_flags`).

Compiling: CasADi generates C (``CodeGenerator``), the system's C compiler (``gcc``, else
``cc``) makes a shared library of it, and ``casadi.external`` loads it. Without a compiler, or
with ``HEXAPOD_NO_JIT=1``, :func:`compiled` returns the interpreted Function; a compiler that
fails is said in a :class:`CompilerWarning` and the interpreted Function is used.
"""

from __future__ import annotations

import contextlib
import functools
import os
import shutil
import struct
import sys
import warnings
from collections.abc import Callable
from pathlib import Path

import casadi as ca

from hexapod._support import cache
from hexapod._support.files import write_atomically
from hexapod.errors import HexapodError

#: Flags of the C compiler on any machine: the tree-ordered inverse dynamics runs 5 to 7 times
#: faster than in CasADi's interpreter.
COMPILER_FLAGS = ("-O2",)
#: ... and on x86-64 Linux, where the processor's features can be read (and go in the key): the
#: processor's own instruction set (fused multiply-adds, wider registers). The walking robot's
#: compiled inverse dynamics, 501 samples: 200 -> 178 us a sample (results within 1e-14 of
#: -O2's: the fused operations round once).
NATIVE_FLAGS = ("-march=native",)
#: The files of a compiled entry: the library and the name of the Function it holds.
LIBRARY, NAME = "library" + (".dll" if sys.platform == "win32" else
                             ".dylib" if sys.platform == "darwin" else ".so"), "name.txt"


class CompilerWarning(UserWarning):
    """The C compiler failed: the interpreted Function is used (same numbers, slower)."""


def compiler() -> str | None:
    """The C compiler used (a path), or None: none found, or ``HEXAPOD_NO_JIT`` set."""
    if os.environ.get("HEXAPOD_NO_JIT"):
        return None
    return shutil.which("gcc") or shutil.which("cc")


def compiled_key(key: str, command: str) -> str:
    """The cache key of ``key``'s library, compiled by ``command`` (a compiler's path) with
    :func:`compiler_flags` (and, when they are the processor's own, its features)."""
    return cache.key("compiled", key, f"casadi {ca.__version__}", command,
                     " ".join(compiler_flags()), sys.platform, _machine(),
                     _processor_features())


@functools.cache
def compiler_flags() -> tuple[str, ...]:
    """The C compiler's flags: :data:`COMPILER_FLAGS`, and :data:`NATIVE_FLAGS` where the
    processor's features are known (a library is then kept for those features only)."""
    return COMPILER_FLAGS + (NATIVE_FLAGS if _processor_features() else ())


@functools.cache
def _processor_features() -> str:
    """The feature flags of an x86-64 processor under Linux (``/proc/cpuinfo``), else empty:
    code compiled for one processor's instruction set may not run on another."""
    if sys.platform != "linux" or _machine() != "x86_64":
        return ""
    with contextlib.suppress(OSError), open("/proc/cpuinfo", encoding="latin-1") as lines:
        for line in lines:
            if line.startswith("flags"):
                return " ".join(line.partition(":")[2].split())
    return ""


def _machine() -> str:
    """The processor's architecture (``os.uname``: without loading ``platform``, 1 ms)."""
    if hasattr(os, "uname"):
        return os.uname().machine
    import platform

    return platform.machine()


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
        name = files[NAME].decode("ascii").strip()
        if not name.isidentifier():
            raise ValueError(f"{NAME} does not name a C function")
        check_library(files[LIBRARY])
        return ca.external(name, str(path / LIBRARY))
    except KeyError as missing:
        cache.reject(entry_key, f"it has no {missing}")
    except (UnicodeDecodeError, ValueError, RuntimeError) as error:
        cache.reject(entry_key, str(error).splitlines()[0])
    return None


def check_library(data: bytes) -> None:
    """Raise ValueError unless ``data`` is a whole shared library for this machine: an ELF
    file of this interpreter's class, byte order and processor whose headers and segments
    all lie inside it. A truncated library would otherwise end the process when loaded (a bus
    error, no message). Other formats (macOS, Windows) are left to the loader."""
    if sys.platform in ("darwin", "win32"):
        return
    if data[:4] != b"\x7fELF" or len(data) < 64:
        raise ValueError("the library is not an ELF file")
    wide, order = data[4] == 2, "<" if data[5] == 1 else ">"
    if wide != (sys.maxsize > 2**32) or order != ("<" if sys.byteorder == "little" else ">"):
        raise ValueError("the library is for another kind of machine")
    header = struct.unpack_from(order + ("HHIQQQIHHHHHH" if wide else "HHIIIIIHHHHHH"), data, 16)
    kind, machine, phoff, shoff = header[0], header[1], header[4], header[5]
    phentsize, phnum, shentsize, shnum = header[8], header[9], header[10], header[11]
    if kind != 3 or machine != (_own_machine() or machine):  # 3: a shared object
        raise ValueError("the library is not a shared object for this processor")
    if phoff + phnum * phentsize > len(data) or shoff + shnum * shentsize > len(data):
        raise ValueError("the library is truncated (its headers lie past its end)")
    segment = order + ("IIQQQQQQ" if wide else "IIIIIIII")
    for k in range(phnum):
        fields = struct.unpack_from(segment, data, phoff + k * phentsize)
        offset, size = (fields[2], fields[5]) if wide else (fields[1], fields[4])
        if fields[0] in (1, 2) and offset + size > len(data):  # a loaded or dynamic segment
            raise ValueError("the library is truncated (a segment lies past its end)")


@functools.cache
def _own_machine() -> int | None:
    """The ELF processor number of this interpreter's executable (None: not an ELF file)."""
    try:
        with open(sys.executable, "rb") as stream:
            head = stream.read(20)
    except OSError:
        return None
    if head[:4] != b"\x7fELF" or len(head) < 20:
        return None
    return struct.unpack_from("<H" if head[5] == 1 else ">H", head, 18)[0]


def compiled(key: str | None, build: Callable[[], ca.Function], *,
             what: str = "") -> ca.Function:
    """The Function ``build()`` makes, compiled to C with :func:`compiler_flags`:
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
    said = f"{what or function.name()}, compiled {' '.join(compiler_flags())}"
    try:
        with cache.writing(entry_key, said) as folder:
            library = _compile(function, folder, command)
            # loaded before the folder is published or removed: the library stays mapped
            return ca.external(function.name(), str(library))
    except (CompileError, HexapodError) as error:  # nothing was stored
        warnings.warn(str(error), CompilerWarning, stacklevel=2)
        return function


def compiled_graph(function: ca.Function, kind: str, what: str = "") -> ca.Function:
    """``function`` compiled (see :func:`compiled`), its library kept under the hash of its
    serialized graph: Functions that depend on more than the model's content (a plan's rows
    and pivots, a kernel's rows), or on less (not on the laws' numbers, which are inputs),
    share a library exactly when they are the same Function."""
    import hashlib

    graph = hashlib.sha256(function.serialize().encode("utf-8")).hexdigest()
    return compiled(f"{kind}/{function.name()}/{graph}", lambda: function,
                    what=what or f"{kind} {function.name()}")


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
    status, said = _run_compiler([command, *compiler_flags(), "-shared", "-fPIC", str(source),
                                  "-o", str(library)])
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
