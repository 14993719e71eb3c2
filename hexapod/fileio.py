"""Files written whole or not at all."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from hexapod.errors import InputFileError


def read_text(path: str | Path, what: str) -> str:
    """The text of a file, or an :class:`InputFileError` saying why it cannot be read
    (``what`` names the kind of file expected, e.g. ``"scene file"``)."""
    path = Path(path)
    try:
        return path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputFileError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise InputFileError(f"{path}: is a directory, not a {what}") from None
    except (OSError, UnicodeDecodeError) as error:
        raise InputFileError(f"{path}: cannot read the file ({error})") from None


def write_atomically(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` through a temporary file in the same folder, renamed over the
    target when complete: a failure (or an interruption) never leaves a partial file.

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
        with os.fdopen(handle, "w", encoding="utf-8", newline="") as stream:
            stream.write(text)
        os.replace(temporary, path)
    except BaseException as error:
        if os.path.exists(temporary):
            os.unlink(temporary)
        if isinstance(error, OSError):
            raise InputFileError(f"{path}: cannot write the file ({error})") from None
        raise
    return path
