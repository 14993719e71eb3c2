"""A cache on disk of what is slow to build (compiled code), kept under content hashes, so that
the second run of the same model builds nothing.

Off unless asked
----------------
The library uses the cache only when its caller turns it on (the ``cache`` of
:class:`hexapod._support.execution.Execution`): a library call never reads or writes a file
its caller did not ask for. The command line turns it on for its own runs, in the folder the
environment names:

=====================  ======================================================================
``HEXAPOD_CACHE_DIR``  the cache folder; else ``$XDG_CACHE_HOME/hexapod``, else
                       ``~/.cache/hexapod``
``HEXAPOD_CACHE``      ``0`` (or ``off``, ``no``, ``false``): no cache; nothing is read or
                       written, everything is built in each process
``HEXAPOD_CACHE_SIZE`` the most the entries may hold, e.g. ``2G`` (default 1 GiB); beyond it
                       the entries used least recently are removed
=====================  ======================================================================

Layout
------
``FOLDER/v1/KEY/`` holds one entry: its files and ``meta.json`` (what it is, when and by which
versions it was made, the SHA-256 of every file). ``KEY`` is a SHA-256 of what the entry was
built from (:func:`key`). An entry is written in a staging folder (``FOLDER/v1/.staging-PID-*``)
and renamed into place in one step, so that no process ever sees half of one; when two
processes build the same entry at once, both succeed and the first one renamed is kept. An
entry that fails its checks (files that do not match their checksums: corrupted, truncated,
written by something else; a folder or file of another user, or that others may write; a link;
anything but a plain file) is removed, said in a warning, and built again: the cache never
makes a computation fail. The last use of an entry is its folder's modification time, set at
each use. Only folders it made itself are ever removed (``FOLDER`` may be shared with other
files), and only a folder owned by the user and writable by nobody else is used (a cached
library is code that runs).

Nothing here imports CasADi: :mod:`hexapod._support.compiled` puts CasADi Functions in the
cache, and ``hexapod cache`` lists and cleans it.
"""

from __future__ import annotations

import contextlib
import errno
import functools
import hashlib
import json
import os
import re
import shutil
import stat
import sys
import tempfile
import time
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from hexapod._support.execution import DEFAULT_CACHE_SIZE, current
from hexapod._support.files import process_alive, write_atomically
from hexapod._support.limits import parse_size, size_text
from hexapod.errors import HexapodError

#: The environment variables (see the module docstring).
FOLDER_VARIABLE = "HEXAPOD_CACHE_DIR"
SWITCH_VARIABLE = "HEXAPOD_CACHE"
SIZE_VARIABLE = "HEXAPOD_CACHE_SIZE"
#: The layout version: the folder of the entries under the cache folder.
LAYOUT = "v1"
#: An entry's description of itself.
META = "meta.json"
#: Staging and trash folders of processes that are gone, or older than this (s), are removed.
LEFTOVER_AGE = 24 * 3600.0

_KEY = re.compile(r"[0-9a-f]{64}")
_NO_FOLLOW = getattr(os, "O_NOFOLLOW", 0)
_OFF = ("0", "off", "no", "false")
_TAG = ("Signature: 8a477f597d28d172789f06886806bc55\n"
        "# This file is a cache directory tag created by hexapod (compiled code,\n"
        "# rebuilt when missing): see 'hexapod cache --help'.\n")


class CacheWarning(UserWarning):
    """The cache cannot be used (a folder that cannot be written, a bad setting): everything is
    then built in the process, as without a cache."""


# ------------------------------------------------------------------ settings


def folder() -> Path | None:
    """The cache folder of the current execution setting (:mod:`hexapod._support.execution`),
    or None: the library reads and writes nothing unless its caller turned the cache on."""
    return current().cache


def size_limit() -> int:
    """The most the entries may hold, in bytes (the current execution setting's)."""
    return current().cache_size


def configured(environ=None) -> dict:
    """The cache the environment configures for the command line (and for scripts), as the
    keyword arguments of :func:`hexapod._support.execution.executing`: ``cache`` and
    ``cache_size``."""
    return {"cache": configured_folder(environ), "cache_size": configured_size(environ)}


def configured_folder(environ=None) -> Path | None:
    """The cache folder the environment configures for the command line: ``HEXAPOD_CACHE_DIR``,
    else ``$XDG_CACHE_HOME/hexapod``, else ``~/.cache/hexapod``; None when ``HEXAPOD_CACHE=0``
    turns it off."""
    environ = os.environ if environ is None else environ
    if environ.get(SWITCH_VARIABLE, "").strip().lower() in _OFF:
        return None
    given = environ.get(FOLDER_VARIABLE, "").strip()
    if given:
        return Path(given).expanduser()
    xdg = environ.get("XDG_CACHE_HOME", "").strip()
    if xdg and Path(xdg).is_absolute():  # the XDG rule: a relative value is ignored
        return Path(xdg) / "hexapod"
    return Path.home() / ".cache" / "hexapod"


def configured_size(environ=None) -> int:
    """The size limit the environment configures (``HEXAPOD_CACHE_SIZE``, default 1 GiB).

    Raises
    ------
    HexapodError
        When the variable is not a size.
    """
    environ = os.environ if environ is None else environ
    text = environ.get(SIZE_VARIABLE, "").strip()
    if not text:
        return DEFAULT_CACHE_SIZE
    try:
        return parse_size(text)
    except ValueError as error:
        raise HexapodError(f"{SIZE_VARIABLE}={text!r}: {error}") from None


def key(*parts: str) -> str:
    """The key of an entry built from ``parts`` (strings saying everything the entry depends
    on), with the version and the sources of hexapod: a SHA-256, 64 hexadecimal digits. The
    same parts give the same key in every process; an edited source file gives new keys."""
    digest = hashlib.sha256()
    for part in (LAYOUT, _code_identity(), *parts):
        data = str(part).encode("utf-8")
        digest.update(len(data).to_bytes(8, "little"))  # unambiguous: ("ab", "c") != ("a", "bc")
        digest.update(data)
    return digest.hexdigest()


@functools.cache
def _code_identity() -> str:
    """hexapod's version, and the path, size and modification time of each of its source files
    (a stat of each, not a read: half a millisecond): code built from other sources is never
    taken for this one's."""
    from hexapod._version import __version__

    package = Path(__file__).resolve().parent.parent
    files: list[str] = []

    def walk(path: str, prefix: str) -> None:
        with contextlib.suppress(OSError), os.scandir(path) as listing:
            for item in listing:
                if item.is_dir(follow_symlinks=False):
                    if item.name != "__pycache__":
                        walk(item.path, f"{prefix}{item.name}/")
                elif item.name.endswith(".py"):
                    with contextlib.suppress(OSError):
                        status = item.stat()
                        files.append(f"{prefix}{item.name}:{status.st_size}:"
                                     f"{status.st_mtime_ns}")

    walk(str(package), "")
    digest = hashlib.sha256("\n".join(sorted(files)).encode("utf-8")).hexdigest()
    return f"hexapod {__version__} {digest}"


# ------------------------------------------------------------------ the entries


@dataclass(frozen=True)
class Entry:
    """One entry: its key, folder, size (bytes), last use (seconds since the epoch) and what it
    holds (from its ``meta.json``; empty when not read)."""

    key: str
    path: Path
    size: int
    used: float
    what: str = ""


def _entries_folder(root: Path) -> Path:
    return root / LAYOUT


def _folder_size(path: Path) -> int:
    size = 0
    with contextlib.suppress(OSError), os.scandir(path) as files:
        for entry in files:
            with contextlib.suppress(OSError):
                size += entry.stat(follow_symlinks=False).st_size
    return size


def entries(root: Path | None = None, *, describe: bool = False) -> list[Entry]:
    """The entries of the cache folder ``root`` (default: :func:`folder`), least recently used
    first; with ``describe``, each with what it holds. Empty when there is no cache."""
    root = folder() if root is None else root
    if root is None:
        return []
    out = []
    try:
        listing = list(os.scandir(_entries_folder(root)))
    except OSError:
        return []
    for item in listing:
        if not (_KEY.fullmatch(item.name) and item.is_dir(follow_symlinks=False)):
            continue
        try:
            used = item.stat(follow_symlinks=False).st_mtime
        except OSError:  # removed meanwhile
            continue
        what = _read_meta(Path(item.path)).get("what", "?") if describe else ""
        out.append(Entry(item.name, Path(item.path), _folder_size(Path(item.path)), used,
                         str(what)))
    out.sort(key=lambda e: (e.used, e.key))
    return out


def _read_meta(path: Path) -> dict:
    """An entry's ``meta.json`` ({} when it cannot be read: not a plain file of this user's,
    not JSON, or over a megabyte)."""
    try:
        meta = json.loads(_read_private(path / META, 2**20))
    except (OSError, ValueError):
        return {}
    return meta if isinstance(meta, dict) else {}


def _usable(root: Path) -> bool:
    """Whether the entries' folder exists, belongs to this user and nobody else may write in
    it (``os.getuid`` missing: not a POSIX system, nothing to check)."""
    try:
        status = os.stat(_entries_folder(root))
    except OSError:
        return False
    if hasattr(os, "getuid") and (status.st_uid != os.getuid() or status.st_mode & 0o022):
        _warn_once(f"{_entries_folder(root)}: not used as hexapod's cache: it belongs to "
                   "another user or others may write in it (a cached library is code that "
                   f"runs); set {FOLDER_VARIABLE} to a folder of your own")
        return False
    return True


def load(entry_key: str) -> tuple[Path, dict[str, bytes]] | None:
    """The folder and files (name -> content) of the entry ``entry_key``, checked and marked as
    used now; None when there is none (or no cache).

    An entry is read only when its folder and every file in it belong to this user, nobody
    else may write them, no file is a link or larger than the cache's size limit, and every
    file listed in ``meta.json`` matches its checksum. An entry that fails is removed, with a
    :class:`CacheWarning` saying why (once), and the caller builds it again."""
    root = folder()
    if root is None or not _usable(root):
        return None
    path = _entries_folder(root) / entry_key
    try:
        status = os.lstat(path)
    except OSError:  # no such entry
        return None
    try:
        files = _read_entry(path, status, size_limit())
    except FileNotFoundError:  # removed meanwhile by another process (or the meta missing)
        if os.path.lexists(path) and not os.path.lexists(path / META):
            reject(entry_key, "it has no meta.json")
        return None
    except (OSError, ValueError) as error:
        reject(entry_key, str(error))
        return None
    with contextlib.suppress(OSError):
        os.utime(path)  # used now: the last to be evicted
    return path, files


def _read_entry(path: Path, status: os.stat_result, largest: int) -> dict[str, bytes]:
    """The files an entry's ``meta.json`` lists, each checked (see :func:`load`)."""
    _check_private(status, "the entry's folder", directory=True)
    try:
        meta = json.loads(_read_private(path / META, largest))
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise ValueError("its meta.json is not JSON") from None
    listed = meta.get("files") if isinstance(meta, dict) else None
    if not isinstance(listed, dict) or not listed:
        raise ValueError("its meta.json lists no files")
    files = {}
    for name, checksum in listed.items():
        if not isinstance(name, str) or "/" in name or name in ("", ".", "..", META):
            raise ValueError(f"its meta.json lists a bad file name {name!r}")
        data = _read_private(path / name, largest)
        if hashlib.sha256(data).hexdigest() != checksum:
            raise ValueError(f"{name} does not match its checksum")
        files[name] = data
    return files


def _check_private(status: os.stat_result, what: str, *, directory: bool = False) -> None:
    """Refuse what is not a plain file (a folder), or belongs to another user, or others may
    write (``os.getuid`` missing: not a POSIX system, only the kind is checked)."""
    kind = stat.S_ISDIR if directory else stat.S_ISREG
    if not kind(status.st_mode):
        raise ValueError(f"{what} is not a {'folder' if directory else 'plain file'}")
    if hasattr(os, "getuid") and (status.st_uid != os.getuid() or status.st_mode & 0o022):
        raise ValueError(f"{what} belongs to another user or others may write it")


def _read_private(path: Path, largest: int) -> bytes:
    """The content of ``path``, not followed if a link, checked as :func:`_check_private` and
    no larger than ``largest`` bytes before it is read."""
    try:  # a named pipe opens without waiting for a writer, and is refused below
        handle = os.open(path, os.O_RDONLY | _NO_FOLLOW | getattr(os, "O_NONBLOCK", 0))
    except OSError as error:
        if error.errno == errno.ELOOP:
            raise ValueError(f"{path.name} is a link") from None
        raise
    with os.fdopen(handle, "rb") as stream:
        status = os.fstat(handle)
        _check_private(status, path.name)
        if status.st_size > largest:
            raise ValueError(f"{path.name} is larger than the cache's size limit")
        return stream.read()


def reject(entry_key: str, reason: str) -> None:
    """Remove the entry ``entry_key``, found damaged or not trusted (``reason``), saying so in a
    :class:`CacheWarning`: it is built again."""
    root = folder()
    where = _entries_folder(root) / entry_key if root is not None else entry_key
    _warn_once(f"cache entry {where} not used ({reason}): removed, it will be built again")
    discard(entry_key)


def discard(entry_key: str) -> None:
    """Remove the entry ``entry_key`` (when there is one): renamed away in one step, then
    deleted, so that no process finds half of it."""
    root = folder()
    if root is not None and _KEY.fullmatch(entry_key):
        _remove(_entries_folder(root) / entry_key)


def _remove(path: Path) -> bool:
    trash = path.with_name(f".trash-{os.getpid()}-{os.urandom(4).hex()}")
    try:
        os.rename(path, trash)
    except OSError:
        return False
    shutil.rmtree(trash, ignore_errors=True)
    return True


@contextlib.contextmanager
def writing(entry_key: str | None, what: str) -> Iterator[Path]:
    """A folder to build the entry ``entry_key`` in, published as that entry when the block
    ends without error (``what`` says what it holds, for ``hexapod cache info``).

    Without a usable cache (turned off, or its folder cannot be written: a
    :class:`CacheWarning` says so once), or with ``entry_key=None`` (nothing to keep), the
    folder is a temporary one, removed at the end: the caller must have loaded what it built
    before the block ends. When another process published the same entry first, its entry is
    kept and this one dropped. Then the entries used least recently are removed beyond the size
    limit.
    """
    limit = size_limit()  # a bad setting is said before the build, not after it
    root = _prepared(folder()) if entry_key is not None else None
    if root is None:
        with tempfile.TemporaryDirectory(prefix="hexapod-build-") as scratch:
            yield Path(scratch)
        return
    staging = Path(tempfile.mkdtemp(prefix=f".staging-{os.getpid()}-",
                                    dir=_entries_folder(root)))
    try:
        yield staging
        try:
            _publish(staging, entry_key, what)
        except (OSError, HexapodError) as error:  # a full disk: the work is done, not kept
            _warn_once(f"cannot keep {what} in the cache folder {root} ({error}): it will be "
                       "built again in the next run")
    finally:
        shutil.rmtree(staging, ignore_errors=True)  # dropped, or left by a failed build
    _evict(root, limit, keep=entry_key)


def keep(entry_key: str, what: str, files: dict[str, bytes | str], *,
         stacklevel: int = 1) -> None:
    """Publish ``files`` (name -> content) as the entry ``entry_key`` (see :func:`writing`);
    where they cannot be written (a full disk), a :class:`CacheWarning` says so (attributed as
    the caller's own ``warnings.warn(..., stacklevel=stacklevel)`` would be), and the run goes
    on: what was built is used, only not kept. Nothing is written when there is no cache."""
    if folder() is None:
        return
    try:
        with writing(entry_key, what) as staging:
            for name, data in files.items():
                write_atomically(staging / name, data, durable=False)
    except HexapodError as error:
        warnings.warn(f"{error}: not kept in the cache", CacheWarning, stacklevel=stacklevel + 1)


def _prepared(root: Path | None) -> Path | None:
    """``root`` with its entries' folder made (mode 0700) and tagged, or None (with a warning
    once) when it cannot be used."""
    if root is None:
        return None
    entries_folder = _entries_folder(root)
    try:
        entries_folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        tag = root / "CACHEDIR.TAG"  # backup tools skip folders so tagged
        if not tag.exists():
            with contextlib.suppress(HexapodError):
                write_atomically(tag, _TAG, durable=False)
    except OSError as error:
        _warn_once(f"cannot write in the cache folder {root} ({error.strerror or error}): "
                   f"everything is built again in each run; set {FOLDER_VARIABLE} to a folder "
                   f"you can write, or {SWITCH_VARIABLE}=0")
        return None
    if not _usable(root):
        return None
    _remove_leftovers(entries_folder)
    return root


def _publish(staging: Path, entry_key: str, what: str) -> None:
    """Write the staging folder's ``meta.json`` and rename the folder to the entry's name."""
    files = {}
    for item in sorted(os.scandir(staging), key=lambda e: e.name):
        if item.is_file(follow_symlinks=False):
            with open(item.path, "rb") as stream:
                files[item.name] = hashlib.file_digest(stream, "sha256").hexdigest()
    from hexapod._version import __version__

    meta = {"what": what, "files": files, "created": int(time.time()), "hexapod": __version__,
            "python": sys.version.split()[0]}
    write_atomically(staging / META, json.dumps(meta, indent=1) + "\n", durable=False)
    try:
        os.rename(staging, staging.with_name(entry_key))
    except OSError:  # published meanwhile by another process: that entry is kept
        pass


# ------------------------------------------------------------------ size and cleaning


def _evict(root: Path, limit: int, keep: str = "") -> None:
    """Remove the entries used least recently until the rest hold at most ``limit`` bytes
    (``keep``, the entry just written, goes last)."""
    listed = entries(root)
    total = sum(e.size for e in listed)
    if total <= limit:
        return
    listed.sort(key=lambda e: e.key == keep)  # stable: least recently used first otherwise
    for entry in listed:
        if total <= limit:
            break
        if _remove(entry.path):
            total -= entry.size


def _remove_leftovers(entries_folder: Path) -> None:
    """Remove the staging and trash folders of processes that are gone (killed while writing
    or removing an entry), and any older than :data:`LEFTOVER_AGE`."""
    now = time.time()
    with contextlib.suppress(OSError), os.scandir(entries_folder) as listing:
        for item in listing:
            kind, _, rest = item.name.partition("-")
            if kind not in (".staging", ".trash"):
                continue
            pid = rest.partition("-")[0]
            with contextlib.suppress(OSError):
                old = now - item.stat(follow_symlinks=False).st_mtime > LEFTOVER_AGE
                if old or not pid.isdigit() or not process_alive(int(pid)):
                    shutil.rmtree(item.path, ignore_errors=True)


def clean(root: Path | None = None, *, unused_for: float | None = None,
          keep_size: int | None = None) -> tuple[int, int]:
    """Remove entries of the cache folder ``root`` (default: :func:`folder`): every one, or
    those not used for ``unused_for`` seconds, or the least recently used until the rest hold
    at most ``keep_size`` bytes (both given: both rules). Returns the number of entries removed
    and the bytes freed. Only entries and the leftovers of processes that are gone are removed:
    nothing else in the folder is touched."""
    root = folder() if root is None else root
    if root is None:
        return 0, 0
    listed = entries(root)
    doomed = set()
    if unused_for is None and keep_size is None:
        doomed = {e.key for e in listed}
    if unused_for is not None:
        doomed |= {e.key for e in listed if time.time() - e.used > unused_for}
    if keep_size is not None:
        total = sum(e.size for e in listed if e.key not in doomed)
        for entry in listed:
            if total <= keep_size:
                break
            if entry.key not in doomed:
                doomed.add(entry.key)
                total -= entry.size
    removed = freed = 0
    for entry in listed:
        if entry.key in doomed and _remove(entry.path):
            removed += 1
            freed += entry.size
    if _entries_folder(root).is_dir():
        _remove_leftovers(_entries_folder(root))
    return removed, freed


def summary() -> dict:
    """What ``hexapod cache info`` says: the folder (None when the cache is off), its entries
    (count and bytes) and the size limit (bytes, and as a person reads it)."""
    root = folder()
    listed = entries(root) if root is not None else []
    limit = size_limit()
    return {"folder": None if root is None else str(root), "entries": len(listed),
            "size": sum(e.size for e in listed), "limit": limit, "limit_text": size_text(limit)}


_warned: set[str] = set()


def _warn_once(message: str) -> None:
    if message not in _warned:
        _warned.add(message)
        warnings.warn(message, CacheWarning, stacklevel=3)
