"""Result directories read back (``hexapod export``): a :class:`Recording` of the scene a
simulation or a liaison force report was run on, its saved times and, for a simulation, its
saved states; every array's shape checked from its header before any data is read, so that a
damaged or crafted file is one clear error in bounded memory.
"""

from __future__ import annotations

import csv
import io
import json
import math
import re
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hexapod._support.limits import max_memory, size_text
from hexapod.errors import InputFileError


@dataclass
class Recording:
    """What a result directory holds.

    Attributes
    ----------
    kind : str
        ``"simulation"`` or ``"report"``.
    directory : Path
    scene : str or None
        The scene it was run on (a file's path or a built-in scene's name), when it says.
    scene_file : str
        The file that says it (for messages).
    t : ndarray (N,)
    q, v, lam : ndarray or None
        Saved states of a simulation (None for a report).
    coordinates : list of str or None
        The coordinate names of a simulation.
    columns : list of str or None
        The CSV header of a report.
    table : ndarray or None
        The CSV rows of a report.
    frame : str
        Axes of a report's wrenches, ``"joint"`` or ``"world"``.
    contact_forces : ndarray (N, m, d) or None
        A contact scheme's run: the ground's force at each unilateral contact, world axes.
    """

    kind: str
    directory: Path
    scene: str | None
    scene_file: str
    t: np.ndarray
    q: np.ndarray | None = None
    v: np.ndarray | None = None
    lam: np.ndarray | None = None
    coordinates: list[str] | None = None
    columns: list[str] | None = None
    table: np.ndarray | None = None
    frame: str = "joint"
    contact_forces: np.ndarray | None = None


def read_recording(directory: str | Path, weigh=None) -> Recording:
    """Read the result directory of ``hexapod simulate`` or ``hexapod report``.

    ``weigh``, when given, is called with the number of saved instants (from an array's header,
    or the CSV's lines) before any of them is read, and raises to refuse them.

    Raises
    ------
    InputFileError
        The directory is missing, is not such a result, or a file in it cannot be read; the
        message names the file and the problem.
    """
    directory = Path(directory)
    if not directory.exists():
        raise InputFileError(f"{directory}: no such directory")
    if not directory.is_dir():
        raise InputFileError(f"{directory}: is a file, not a result directory of 'hexapod "
                             "simulate' or 'hexapod report'")
    if (directory / "results.npz").exists():
        return _read_simulation(directory, weigh)
    if (directory / "inverse.csv").exists():
        return _read_report(directory, weigh)
    raise InputFileError(f"{directory}: not a result directory of 'hexapod simulate' "
                         "(results.npz) or 'hexapod report' (inverse.csv)")


def _npz_headers(path: Path, limit: int) -> dict[str, tuple[tuple, np.dtype]]:
    """The shape and dtype of every array of an ``.npz`` file, from the headers of its members,
    before any data is read: a member whose header declares more data than it holds, or members
    more than ``limit`` bytes in all, are refused (a crafted file of a megabyte declaring arrays
    of terabytes costs nothing)."""
    from numpy.lib import format as npy

    headers = {}
    with zipfile.ZipFile(path) as archive:
        members = [m for m in archive.infolist() if m.filename.endswith(".npy")]
        total = sum(m.file_size for m in members)
        if total > limit:
            raise InputFileError(f"{path}: its arrays hold {size_text(total)}, above the limit "
                                 f"of {size_text(limit)} (HEXAPOD_MAX_MEMORY raises it)")
        for member in members:
            key = member.filename[:-4]
            with archive.open(member) as stream:
                version = npy.read_magic(stream)
                if version not in ((1, 0), (2, 0)):
                    raise ValueError(f"array '{key}': .npy format {version} is not supported")
                read = npy.read_array_header_1_0 if version == (1, 0) \
                    else npy.read_array_header_2_0
                shape, _, dtype = read(stream, max_header_size=10_000)
            size = math.prod(shape) * dtype.itemsize
            if dtype.hasobject or size > member.file_size:
                raise InputFileError(f"{path}: array '{key}' declares shape {shape} ({dtype}, "
                                     f"{size_text(size)}) but holds {size_text(member.file_size)}"
                                     ": the file is damaged or not written by 'hexapod "
                                     "simulate'")
            headers[key] = (shape, dtype)
    return headers


def _check_shapes(path: Path, headers: dict) -> None:
    """The arrays a simulation saves, with one row per saved time (from their headers)."""
    for key in ("t", "q", "v", "lam", "coordinates"):
        if key not in headers:
            raise InputFileError(f"{path}: no array '{key}': not written by 'hexapod simulate'")
    shape = headers["t"][0]
    n = shape[0] if len(shape) == 1 else -1
    for key in ("t", "q", "v", "lam"):
        shape, dtype = headers[key]
        if dtype.kind not in "fi" or len(shape) != (1 if key == "t" else 2) \
                or shape[0] != n:
            raise InputFileError(f"{path}: array '{key}' has shape {shape} "
                                 f"({dtype}), not one row per saved time")
    if "contact_forces" in headers:  # a contact scheme's: (N, m, d)
        shape, dtype = headers["contact_forces"]
        if dtype.kind not in "fi" or len(shape) != 3 or shape[0] != n:
            raise InputFileError(f"{path}: array 'contact_forces' has shape {shape} "
                                 f"({dtype}), not one row of contacts per saved time")


def _read_simulation(directory: Path, weigh) -> Recording:
    from hexapod._support.files import check_input, read_text

    path = directory / "results.npz"
    check_input(path, "results file")
    try:
        headers = _npz_headers(path, max_memory())
        _check_shapes(path, headers)
        if weigh is not None:
            weigh(headers["t"][0][0])
        with np.load(path, allow_pickle=False) as saved:
            arrays = {key: saved[key] for key in saved.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as error:
        raise InputFileError(f"{path}: cannot read the file ({error})") from None
    t = np.asarray(arrays["t"])
    n = t.shape[0]
    for key in ("t", "q", "v", "lam", "contact_forces"):
        array = arrays.get(key, np.zeros(0))
        if not np.all(np.isfinite(array)):
            raise InputFileError(f"{path}: array '{key}' holds non-finite numbers")
    if n == 0:
        raise InputFileError(f"{path}: no saved state")
    scene, said_by = None, str(path)
    if "source" in arrays and arrays["source"].ndim == 0:
        scene = str(arrays["source"])
    else:  # written before results recorded their scene: a built-in scene's name may do
        stats = directory / "stats.json"
        try:
            name = json.loads(read_text(stats, "statistics file")).get("scene")
        except (InputFileError, ValueError, AttributeError):
            name = None
        if isinstance(name, str) and name:
            scene, said_by = name, str(stats)
    return Recording("simulation", directory, scene, said_by, t.astype(float),
                     q=arrays["q"].astype(float), v=arrays["v"].astype(float),
                     lam=arrays["lam"].astype(float),
                     coordinates=[str(c) for c in arrays["coordinates"]],
                     contact_forces=(arrays["contact_forces"].astype(float)
                                     if "contact_forces" in arrays else None))


_SCENE_LINE = re.compile(r"^Scene `([^`]*)`", re.M)


#: bytes of memory reading a report's CSV needs per byte of the file (its text, and the
#: careful parser's rows of strings when the fast one cannot read it)
REPORT_MEMORY_PER_BYTE = 20


def _report_table(path: Path, header: list[str], body: str) -> np.ndarray:
    """The numbers of a report CSV's rows (``body``, from line 2): NumPy's parser, else the
    careful one, which says what is wrong and where."""
    if '"' not in body:
        try:
            values = np.loadtxt(io.StringIO(body), delimiter=",", ndmin=2, comments=None)
        except ValueError:
            values = None
        if values is not None and values.shape[1] == len(header) and len(values):
            return values
    table = []
    reader = csv.reader(io.StringIO(body, newline=""))
    try:
        for row in reader:
            number = reader.line_num + 1
            if not row:
                continue
            if len(row) != len(header):
                raise InputFileError(f"{path}: line {number}: {len(row)} values for "
                                     f"{len(header)} columns")
            try:
                table.append([float(x) for x in row])
            except ValueError:
                raise InputFileError(f"{path}: line {number}: not a number in the "
                                     "row") from None
    except csv.Error as error:
        raise InputFileError(f"{path}: line {reader.line_num + 1}: cannot read the CSV "
                             f"({error}): not the CSV of 'hexapod report'") from None
    if not table:
        raise InputFileError(f"{path}: no sample")
    return np.array(table)


def _read_report(directory: Path, weigh) -> Recording:
    from hexapod._support.files import read_text

    path = directory / "inverse.csv"
    text = read_text(path, "report CSV", cost=REPORT_MEMORY_PER_BYTE)
    first, _, body = text.partition("\n")
    try:
        header = next(csv.reader([first]), [])
    except csv.Error as error:
        raise InputFileError(f"{path}: line 1: cannot read the CSV ({error}): not the CSV of "
                             "'hexapod report'") from None
    if not header or header[0] != "t":
        raise InputFileError(f"{path}: line 1: the header does not start with 't': not the CSV "
                             "of 'hexapod report'")
    if weigh is not None:
        weigh(body.count("\n") + (not body.endswith("\n")))
    values = _report_table(path, header, body)
    if not np.all(np.isfinite(values[:, 0])):
        raise InputFileError(f"{path}: non-finite times")
    summary = directory / "summary.md"
    text = read_text(summary, "report summary")
    match = _SCENE_LINE.search(text)
    if match is None:
        raise InputFileError(f"{summary}: no line 'Scene `...`' naming the scene: not the "
                             "summary of 'hexapod report'")
    if "in world axes;" in text:
        frame = "world"
    elif "in the child's joint frame;" in text:
        frame = "joint"
    else:
        raise InputFileError(f"{summary}: does not say in which axes the wrenches are given")
    return Recording("report", directory, match.group(1), str(summary), values[:, 0],
                     columns=header, table=values, frame=frame)
