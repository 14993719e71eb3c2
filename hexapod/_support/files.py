"""Files and directories written whole or not at all; a user's files read through one checked
open (regular files only, weighed before they are read), with clear errors."""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import stat
import sys
import tempfile
from pathlib import Path

from hexapod.errors import InputFileError

# ------------------------------------------------------------------ inputs checked before reading

_KINDS = ((stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISFIFO, "a named pipe"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISLNK, "a symbolic link"), (stat.S_ISDIR, "a directory"),
          (stat.S_ISREG, "a regular file"))


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "a special file")


#: Bytes read at a time once a file turned out larger than it said (a file still growing).
_CHUNK = 1 << 20


def check_input(path: str | Path, what: str) -> os.stat_result:
    """``path`` as an input, checked before it is opened: it must be a regular file (or a
    link to one). A named pipe, a device or a socket is refused with its kind named, since
    reading one may wait for ever or never end.

    Returns
    -------
    os.stat_result
        The file's status.

    Raises
    ------
    InputFileError
        The file is missing, cannot be reached, or is not a regular file.
    """
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise InputFileError(f"{path}: no such file") from None
    except OSError as error:
        raise InputFileError(f"{path}: cannot read the file ({error.strerror})") from None
    if stat.S_ISDIR(info.st_mode):
        raise InputFileError(f"{path}: is a directory, not a {what}")
    if not stat.S_ISREG(info.st_mode):
        raise InputFileError(f"{path}: is {_kind(info.st_mode)}, not a {what}: only a regular "
                             "file is read (a pipe or a device may never end)")
    return info


def open_input(path: str | Path, what: str, *, cost: float = 1.0):
    """A user's file opened for reading (binary), the one checked way in: the file must be a
    regular file (:func:`check_input`, before it is opened; a file swapped for a pipe in
    between is refused too, without waiting on it) and its size weighed against the memory
    limit (:func:`hexapod._support.limits.check_memory`: reading it costs about ``cost``
    bytes of memory a byte), before any of it is read.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        The kind of file expected, for messages (``"scene file"``).
    cost : float
        Bytes of memory its reader needs per byte of the file.

    Returns
    -------
    BinaryIO
        The open file, to be closed by the caller (a context manager).

    Raises
    ------
    InputFileError
        The file is missing, not a regular file, or cannot be opened.
    HexapodError
        Reading it would pass the memory limit.
    """
    from hexapod._support.limits import check_memory, size_text

    info = check_input(path, what)
    check_memory(cost * info.st_size, f"reading the {what} {path} ({size_text(info.st_size)})",
                 f"give a smaller {what}", option=None)
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
    try:
        handle = os.open(path, flags)
    except OSError as error:
        raise InputFileError(f"{path}: cannot read the file ({error.strerror})") from None
    opened = os.fstat(handle)
    if not stat.S_ISREG(opened.st_mode):
        os.close(handle)
        raise InputFileError(f"{path}: is {_kind(opened.st_mode)}, not a {what}: only a "
                             "regular file is read (a pipe or a device may never end)")
    os.set_blocking(handle, True)
    return os.fdopen(handle, "rb")


def read_bytes(path: str | Path, what: str, *, cost: float = 1.0) -> bytes:
    """The content of a user's file, read through :func:`open_input` (refused before it is
    read when it is not a regular file or would pass the memory limit), and never more than
    the limit allows if it grows while it is read."""
    from hexapod._support.limits import check_memory, max_memory

    budget = int(max_memory() / max(cost, 1.0))
    with open_input(path, what, cost=cost) as stream:
        try:
            size = os.fstat(stream.fileno()).st_size
            chunks, total = [], 0
            while chunk := stream.read(size + 1 if not chunks else _CHUNK):
                chunks.append(chunk)
                total += len(chunk)
                if total > budget:
                    check_memory(cost * total, f"reading the {what} {path} (still growing)",
                                 f"give a smaller {what}", option=None)
        except OSError as error:
            raise InputFileError(f"{path}: cannot read the file ({error.strerror})") from None
    return b"".join(chunks)


def read_toml(path: str | Path, what: str) -> dict:
    """A user's TOML file parsed (``what``: the kind of file, e.g. ``"study file"``), or an
    :class:`InputFileError` naming the file and why: unreadable (:func:`read_text`), not
    valid TOML, or nested too deeply for the parser (tomllib recurses)."""
    import tomllib

    path = Path(path)
    text = read_text(path, what)
    try:
        return tomllib.loads(text)
    except ValueError as error:  # a TOMLDecodeError, or an integer of thousands of digits
        reason = str(error).split(";")[0]  # not Python's advice on its digit limit
        raise InputFileError(f"{path}: not valid TOML: {reason}") from None
    except RecursionError:
        raise InputFileError(f"{path}: arrays or tables nested too deeply to be read as a "
                             "TOML file") from None


def read_text(path: str | Path, what: str, *, cost: float = 50.0) -> str:
    """The text of a user's file, or an :class:`InputFileError` saying why it cannot be read
    (``what`` names the kind of file expected, e.g. ``"scene file"``). The file is checked
    before it is read (:func:`read_bytes`; ``cost``: bytes of memory its parser needs per
    byte, 50 for TOML or XML). The text is UTF-8; a byte-order mark at its start, as some
    editors write, is dropped."""
    path = Path(path)
    data = read_bytes(path, what, cost=cost)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        line = data[:error.start].count(b"\n") + 1
        raise InputFileError(f"{path}: not UTF-8 text (byte 0x{data[error.start]:02x} on line "
                             f"{line}); a {what} must be saved as UTF-8") from None


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _sync(stream) -> None:
    """Flush a file to the disk before it is renamed into place, so that a crash of the machine
    cannot leave the new name on an empty file."""
    stream.flush()
    os.fsync(stream.fileno())


# ------------------------------------------------------------------ outputs checked before work

#: Characters the temporary names add to an output's name (``.NAME.PID.XXXXXXXX.tmp``).
_TEMPORARY_EXTRA = 40


def _inside(path: Path, folder: Path) -> bool:
    try:
        path.resolve().relative_to(folder.resolve())
    except (ValueError, OSError, RuntimeError):
        return False
    return True


def check_output(path: str | Path, *, option: str, inputs=(), directory: bool = False,
                 ours=None) -> Path:
    """``path`` as an output, checked before any work: writing it must harm nothing.

    A file output may replace only a regular file, a directory output only a directory the
    project wrote (every entry a regular file that ``ours(name)`` accepts; see
    :func:`write_directory_atomically`; ``ours=None`` leaves its contents to the caller).
    Neither may be, or hold, one of ``inputs`` (files the command reads). The folder it goes in
    must exist, and its name must leave room for the temporary name it is written under. A
    directory left half-swapped by an earlier run that was killed is put right first
    (:func:`recover_directory`).

    Raises
    ------
    InputFileError
        What is wrong, with ``option`` and the path; nothing is touched.
    """
    path = Path(path)
    said = f"{option} {path}"
    if not str(path) or path.name in ("", ".", ".."):
        raise InputFileError(f"{said}: not a file name")
    parent = path.parent
    try:
        if not parent.is_dir():
            raise InputFileError(f"{said}: no folder {parent} to write into")
        name_max = os.pathconf(parent, "PC_NAME_MAX")
    except OSError as error:
        raise InputFileError(f"{said}: cannot use the path ({error.strerror})") from None
    if len(os.fsencode(path.name)) + _TEMPORARY_EXTRA > name_max:
        raise InputFileError(f"{said}: the name is too long for the file system (at most "
                             f"{name_max - _TEMPORARY_EXTRA} bytes here, to leave room for the "
                             "temporary name it is written under)")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputFileError(f"{said}: cannot write in the folder {parent} (permission denied)")
    if directory:
        recover_directory(path)
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return path
    except OSError as error:
        raise InputFileError(f"{said}: cannot use the path ({error.strerror})") from None
    wanted = stat.S_ISDIR if directory else stat.S_ISREG
    if not wanted(mode):
        expected = "a directory" if directory else "a regular file"
        raise InputFileError(f"{said}: exists and is {_kind(mode)}, not {expected}; nothing "
                             "but " + ("a directory this program wrote" if directory else
                                       "a regular file") + " is ever replaced: choose another "
                             "output")
    for given in inputs:
        given = Path(given)
        if not given.exists():
            continue
        same = (_inside(given, path) if directory else os.path.samefile(given, path))
        if same:
            where = "holds" if directory else "is"
            raise InputFileError(f"{said}: {where} the input {given}; writing it would destroy "
                                 "what the command reads: choose another output")
    if directory and ours is not None:
        _check_ours(path, said, ours)
    return path


def _check_ours(path: Path, said: str, ours) -> None:
    foreign = []
    with os.scandir(path) as entries:
        for entry in entries:
            if not entry.is_file(follow_symlinks=False) or not ours(entry.name):
                foreign.append(entry.name)
                if len(foreign) > 3:
                    break
    if foreign:
        shown = ", ".join(sorted(foreign)[:3]) + (", ..." if len(foreign) > 3 else "")
        raise InputFileError(f"{said}: exists and holds other files ({shown}) than this "
                             "command writes; choose another output directory or empty this one")


def default_output(name: str, option: str = "--out") -> Path:
    """The output a command writes when ``option`` is not given: ``name`` in the current folder,
    said in one line on stderr."""
    print(f"hexapod: no {option} given: writing {name} in the current folder", file=sys.stderr)
    return Path(name)


# ------------------------------------------------------------------ files written whole


def _temporary_prefix(path: Path) -> str:
    """Temporary names carry the writer's process id, so that the next writer of the same
    output can tell the leftovers of a killed run (their process gone) from a live one's."""
    return f".{path.name}.{os.getpid()}."


def _remove_leftovers(path: Path) -> None:
    """Remove the temporary files and folders of ``path`` left by writers that were killed."""
    parent = path.parent if str(path.parent) else Path(".")
    head = f".{path.name}."
    try:
        entries = [e for e in os.scandir(parent) if e.name.startswith(head)
                   and e.name.endswith(".tmp")]
    except OSError:
        return
    for entry in entries:
        pid = entry.name[len(head):].split(".", 1)[0]
        if not pid.isdigit() or process_alive(int(pid)):
            continue
        if entry.is_dir(follow_symlinks=False):
            shutil.rmtree(entry.path, ignore_errors=True)
        else:
            with contextlib.suppress(OSError):
                os.unlink(entry.path)


def process_alive(pid: int) -> bool:
    """Whether the process ``pid`` exists (one of another user's counts as alive): the owner of
    a leftover temporary file or folder, which is removed only once its writer is gone."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # someone else's process, alive
        return True
    return True


def write_atomically(path: str | Path, text: str | bytes, *, durable: bool = True) -> Path:
    """Write ``text`` (UTF-8, or ``bytes`` as they are) to ``path`` through a temporary file in
    the same folder, renamed over the target when complete: a failure (or an interruption)
    never leaves a partial file. Only a regular file is ever replaced. With ``durable`` (the
    default, for outputs) the file is on the disk before it is renamed, so that not even a
    crash of the machine can leave the new name on an empty file; ``durable=False`` skips that
    wait, for files whose loss is harmless (the cache's, which checks what it reads).

    Parameters
    ----------
    path : str or Path
        The file to write.
    text : str or bytes
        Its content.
    durable : bool
        Flush the file to the disk before it is renamed.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    InputFileError
        The file cannot be written, or ``path`` is not a regular file; the target is left as
        it was.
    """
    path = Path(path)
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        mode = None
    except OSError as error:
        raise InputFileError(f"{path}: cannot write the file ({error.strerror})") from None
    if mode is not None and not stat.S_ISREG(mode):
        raise InputFileError(f"{path}: exists and is {_kind(mode)}, not a regular file; it is "
                             "not replaced: choose another output")
    _remove_leftovers(path)
    try:
        handle, temporary = tempfile.mkstemp(dir=path.parent or ".",
                                             prefix=_temporary_prefix(path), suffix=".tmp")
    except OSError as error:
        raise InputFileError(f"{path}: cannot write the file ({error})") from None
    try:
        os.chmod(temporary, 0o666 & ~_umask())  # as open() would create it (mkstemp: 0600)
        binary = isinstance(text, bytes)
        with (os.fdopen(handle, "wb") if binary else
              os.fdopen(handle, "w", encoding="utf-8", newline="")) as stream:
            stream.write(text)
            if durable:
                _sync(stream)
        os.replace(temporary, path)
    except BaseException as error:
        if os.path.exists(temporary):
            os.unlink(temporary)
        if isinstance(error, OSError):
            raise InputFileError(f"{path}: cannot write the file ({error})") from None
        raise
    return path


# ------------------------------------------------------------------ directories written whole


def _backup(path: Path) -> Path:
    """Where the earlier output waits while the new one is moved in (when the system cannot
    exchange two names at once)."""
    return path.with_name(f".{path.name}.old")


def recover_directory(path: str | Path) -> None:
    """Put right what a writer of the directory ``path`` killed mid-way left: the earlier output
    moved aside but the new one not yet in (it is moved back), or both in place (the earlier one
    is removed); and temporary folders of writers no longer running."""
    path = Path(path)
    backup = _backup(path)
    if backup.is_dir() and not backup.is_symlink():
        if path.exists() or path.is_symlink():
            shutil.rmtree(backup, ignore_errors=True)
        else:
            with contextlib.suppress(OSError):
                os.replace(backup, path)
    _remove_leftovers(path)


def _exchange(first: Path, second: Path) -> bool:
    """Swap two names in one atomic step (Linux ``renameat2`` with ``RENAME_EXCHANGE``); False
    where the system or the file system cannot."""
    if not sys.platform.startswith("linux"):
        return False
    import ctypes  # here only: 1.4 ms of every command's start otherwise

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                          ctypes.c_uint]
    at_cwd, exchange = -100, 2  # AT_FDCWD, RENAME_EXCHANGE
    if renameat2(at_cwd, os.fsencode(first), at_cwd, os.fsencode(second), exchange) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP, errno.EOPNOTSUPP):
        return False
    raise OSError(code, os.strerror(code), str(second))


def _swap_in(staging: Path, path: Path) -> None:
    """Move the complete ``staging`` directory to ``path``, which holds an earlier output: one
    atomic exchange where the system offers it, else two renames through :func:`_backup`, which
    :func:`recover_directory` completes or undoes if the process dies between them."""
    if _exchange(staging, path):
        shutil.rmtree(staging, ignore_errors=True)  # now the earlier output
        return
    backup = _backup(path)
    os.replace(path, backup)
    try:
        os.replace(staging, path)
    except BaseException:
        os.replace(backup, path)  # put the earlier output back
        raise
    shutil.rmtree(backup, ignore_errors=True)


def staging_directory(path: str | Path) -> Path:
    """A new empty directory beside ``path``, to be filled and then moved in with
    :func:`swap_directory`: its temporary name carries this process's id, so that the next
    writer of ``path`` removes it if this process dies first (:func:`recover_directory`).

    Raises
    ------
    InputFileError
        The directory cannot be made.
    """
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    try:
        staging = Path(tempfile.mkdtemp(dir=parent, prefix=_temporary_prefix(path),
                                        suffix=".tmp"))
        os.chmod(staging, 0o777 & ~_umask())  # as mkdir would make it (mkdtemp: 0700)
    except OSError as error:
        raise InputFileError(f"{path}: cannot write the directory ({error})") from None
    return staging


def swap_directory(staging: str | Path, path: str | Path) -> Path:
    """Move the complete directory ``staging`` (:func:`staging_directory`) to ``path`` in one
    step; an earlier directory there is replaced whole and then removed (its links are removed,
    never followed). The caller checks first that the earlier directory is its own output.

    Raises
    ------
    InputFileError
        The directory cannot be moved; ``path`` is left as it was.
    """
    staging, path = Path(staging), Path(path)
    try:
        if path.exists() or path.is_symlink():
            _swap_in(staging, path)
        else:
            os.replace(staging, path)
    except OSError as error:
        raise InputFileError(f"{path}: cannot write the directory ({error})") from None
    return path


def write_directory_atomically(path: str | Path, files: dict[str, bytes]) -> Path:
    """Write ``files`` (name -> content) as the directory ``path``: a temporary directory
    beside it, filled and then swapped with ``path``, so that the directory appears complete or
    not at all, and the earlier output stays whole until the new one is complete. An existing
    ``path`` is replaced only when it holds nothing but files of those names (an earlier run's
    output); anything else is an error and is left untouched.

    Parameters
    ----------
    path : str or Path
        The directory to write.
    files : dict of str to bytes
        Its files' contents by name.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    InputFileError
        The directory cannot be written, or ``path`` holds something else.
    """
    path = Path(path)
    recover_directory(path)
    if path.exists() or path.is_symlink():
        if not path.is_dir() or path.is_symlink():
            raise InputFileError(f"{path}: exists and is not a directory; choose another output")
        _check_ours(path, str(path), lambda name: name in files)
    parent = path.parent if str(path.parent) else Path(".")
    try:
        staging = Path(tempfile.mkdtemp(dir=parent, prefix=_temporary_prefix(path),
                                        suffix=".tmp"))
    except OSError as error:
        raise InputFileError(f"{path}: cannot write the directory ({error})") from None
    try:
        os.chmod(staging, 0o777 & ~_umask())  # as mkdir would make it (mkdtemp: 0700)
        for name, content in files.items():
            with open(staging / name, "wb") as stream:
                stream.write(content)
                _sync(stream)
        if path.exists():
            _swap_in(staging, path)
        else:
            os.replace(staging, path)
    except BaseException as error:
        shutil.rmtree(staging, ignore_errors=True)
        if isinstance(error, OSError):
            raise InputFileError(f"{path}: cannot write the directory ({error})") from None
        raise
    return path
