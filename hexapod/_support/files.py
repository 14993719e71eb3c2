"""Files and directories written whole or not at all; text files read with clear errors."""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

from hexapod.errors import InputFileError


def read_text(path: str | Path, what: str) -> str:
    """The text of a file, or an :class:`InputFileError` saying why it cannot be read
    (``what`` names the kind of file expected, e.g. ``"scene file"``). The text is UTF-8; a
    byte-order mark at its start, as some editors write, is dropped."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise InputFileError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise InputFileError(f"{path}: is a directory, not a {what}") from None
    except OSError as error:
        raise InputFileError(f"{path}: cannot read the file ({error})") from None
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


def write_atomically(path: str | Path, text: str | bytes) -> Path:
    """Write ``text`` (UTF-8, or ``bytes`` as they are) to ``path`` through a temporary file in
    the same folder, renamed over the target when complete: a failure (or an interruption)
    never leaves a partial file.

    Raises
    ------
    InputFileError
        The file cannot be written; the target is left as it was.
    """
    path = Path(path)
    try:
        handle, temporary = tempfile.mkstemp(dir=path.parent or ".", prefix=f".{path.name}.",
                                             suffix=".tmp")
    except OSError as error:
        raise InputFileError(f"{path}: cannot write the file ({error})") from None
    try:
        os.chmod(temporary, 0o666 & ~_umask())  # as open() would create it (mkstemp: 0600)
        binary = isinstance(text, bytes)
        with (os.fdopen(handle, "wb") if binary else
              os.fdopen(handle, "w", encoding="utf-8", newline="")) as stream:
            stream.write(text)
            _sync(stream)
        os.replace(temporary, path)
    except BaseException as error:
        if os.path.exists(temporary):
            os.unlink(temporary)
        if isinstance(error, OSError):
            raise InputFileError(f"{path}: cannot write the file ({error})") from None
        raise
    return path


def write_directory_atomically(path: str | Path, files: dict[str, bytes]) -> Path:
    """Write ``files`` (name -> content) as the directory ``path``: a temporary directory
    beside it, filled and then renamed to ``path``, so that the directory appears complete or
    not at all. An existing ``path`` is replaced only when it holds nothing but files of those
    names (an earlier run's output); anything else is an error and is left untouched.

    Raises
    ------
    InputFileError
        The directory cannot be written, or ``path`` holds something else.
    """
    path = Path(path)
    if path.exists() or path.is_symlink():
        if not path.is_dir() or path.is_symlink():
            raise InputFileError(f"{path}: exists and is not a directory; choose another output")
        foreign = sorted(p.name for p in path.iterdir() if p.name not in files or not p.is_file())
        if foreign:
            shown = ", ".join(foreign[:3]) + (", ..." if len(foreign) > 3 else "")
            raise InputFileError(f"{path}: exists and holds other files ({shown}); choose "
                                 "another output directory or empty this one")
    parent = path.parent if str(path.parent) else Path(".")
    try:
        staging = Path(tempfile.mkdtemp(dir=parent, prefix=f".{path.name}.", suffix=".tmp"))
    except OSError as error:
        raise InputFileError(f"{path}: cannot write the directory ({error})") from None
    retired = None
    try:
        os.chmod(staging, 0o777 & ~_umask())  # as mkdir would make it (mkdtemp: 0700)
        for name, content in files.items():
            with open(staging / name, "wb") as stream:
                stream.write(content)
                _sync(stream)
        if path.exists():
            retired = Path(tempfile.mkdtemp(dir=parent, prefix=f".{path.name}.", suffix=".old"))
            os.rmdir(retired)
            os.replace(path, retired)
        os.replace(staging, path)
    except BaseException as error:
        if retired is not None and retired.exists() and not path.exists():
            os.replace(retired, path)  # put the earlier output back
        shutil.rmtree(staging, ignore_errors=True)
        if isinstance(error, OSError):
            raise InputFileError(f"{path}: cannot write the directory ({error})") from None
        raise
    if retired is not None:
        shutil.rmtree(retired, ignore_errors=True)
    return path
