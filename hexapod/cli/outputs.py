"""Where a command writes: its output checked before any work, or its default said.

Every command that writes calls :func:`output_file` or :func:`output_directory` before it reads
or computes anything heavy, so that an output that would harm something (a device node, a file
the command reads, a folder of someone else's files) is refused at once, with the option named,
rather than after minutes of work. Nothing here imports NumPy.
"""

from __future__ import annotations

from pathlib import Path

from hexapod._support.files import check_output, default_output


def given_files(*values) -> list[Path]:
    """The files named on the command line that exist (a built-in scene's name is not one)."""
    return [Path(value) for value in values if value and Path(value).exists()]


def output_file(value: str, *, option: str = "--out", inputs=()) -> Path:
    """The file ``value`` given with ``option``, checked (:func:`check_output`)."""
    return check_output(value, option=option, inputs=inputs)


def output_directory(value: str | None, default: str, *, option: str = "--out", inputs=(),
                     ours=None) -> Path:
    """The directory given with ``option``, or ``default`` in the current folder (said in one
    line), checked (:func:`check_output`): it may replace only a directory whose every file
    ``ours(name)`` accepts."""
    path = Path(value) if value else default_output(default, option)
    return check_output(path, option=option, inputs=inputs, directory=True, ours=ours)


def suffixes(*endings: str):
    """``ours`` for :func:`output_directory`: the names ending so (e.g. ``".csv"``)."""
    return lambda name: name.endswith(endings)
