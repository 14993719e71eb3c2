"""Motion files: a prescribed motion of a model's joints, sample by sample (CSV).

Columns: ``t`` (s, strictly increasing), then one column per driven joint named as in the model
(rad for revolute joints, m for prismatic joints, whatever the scene's length unit), and
optionally ``qd:<joint>`` and ``qdd:<joint>`` with exact first and second derivatives. Each
joint becomes a driver whose law passes through the samples:

* with ``qd`` and ``qdd``: the quintic Hermite interpolant, exact at every sample (C2);
* with ``qd`` only: the same, with ``qdd`` the derivative of a C2 spline through ``qd``;
* with neither: a C2 (cubic, not-a-knot) interpolating spline, whose derivatives are used.

The last two warn (:class:`MotionWarning`, one warning naming every such joint), since the
derivatives are then estimated.
"""

from __future__ import annotations

import csv
import io
import math
import warnings
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hexapod._support.files import read_text
from hexapod.errors import InputFileError, ModelError, Problem
from hexapod.scene.drivers import JointDriver
from hexapod.scene.element import quoted
from hexapod.scene.joints import kinds_that
from hexapod.scene.laws import Hermite, Law, Spline
from hexapod.scene.scene import Scene

#: problems of a motion file listed one by one; beyond, they are counted
_SHOWN = 20
#: bytes of memory reading a motion needs per byte of the file (17 measured on a quoted file,
#: which the careful parser reads; 7.5 for a plain one): weighed before the file is read
MEMORY_PER_BYTE = 20


class MotionWarning(UserWarning):
    """Derivatives of a motion were estimated by a spline rather than given."""


@dataclass(frozen=True)
class Motion:
    """Samples of joint coordinates (SI), with the derivatives that were given.

    Attributes
    ----------
    times : ndarray, shape (N,)
        Sample times, s.
    values : dict of str to ndarray, shape (N,)
        Each joint's coordinate (rad or m), by joint name.
    rates, accelerations : dict of str to ndarray, shape (N,)
        Their first and second time derivatives where the file gives them (rad/s, m/s;
        rad/s^2, m/s^2).
    source : str
        The file read, named in messages.
    """

    times: np.ndarray
    values: dict[str, np.ndarray]
    rates: dict[str, np.ndarray]
    accelerations: dict[str, np.ndarray]
    source: str = ""

    @property
    def joints(self) -> tuple[str, ...]:
        return tuple(self.values)


def _fast_table(text: str) -> tuple[list[str], np.ndarray] | None:
    """Header and numbers of a well-formed file, parsed by NumPy; None when anything is off
    (the careful parser then says what)."""
    header, _, body = text.partition("\n")
    try:
        data = np.loadtxt(io.StringIO(body), delimiter=",", ndmin=2)
    except ValueError:
        return None
    names = [cell.strip() for cell in header.split(",")]
    if data.shape[1] != len(names) or data.shape[0] < 2 or not np.all(np.isfinite(data)):
        return None
    return names, data


def read_motion(path: str | Path) -> Motion:
    """Read a motion CSV file; every problem is named with the file, line and column.

    The columns are ``t`` (s) and one per joint coordinate (rad or m, SI), with optional
    ``qd:<joint>`` and ``qdd:<joint>`` for its rates and accelerations.

    Parameters
    ----------
    path : str or Path
        The CSV file.

    Returns
    -------
    Motion

    Raises
    ------
    InputFileError
        The file is missing, unreadable, empty or not CSV.
    ModelError
        A value is not a finite number, a line has the wrong number of values, or there are
        fewer than 2 samples; every problem is listed.
    """
    path = Path(path)
    text = read_text(path, "motion file", cost=MEMORY_PER_BYTE)
    fast = _fast_table(text) if '"' not in text else None
    try:
        rows = [] if fast else list(csv.reader(io.StringIO(text, newline="")))
    except csv.Error as error:
        raise InputFileError(f"{path}: cannot read the motion file ({error})") from None
    if fast:
        header, data = fast
        return _motion(path, header, data, [])
    rows = [row for row in rows if row and any(cell.strip() for cell in row)]
    if not rows:
        raise InputFileError(f"{path}: the motion file is empty")
    header = [cell.strip() for cell in rows[0]]
    problems: list[Problem] = []

    def problem(where: str, message: str):
        problems.append(Problem("motion", message, f"{path}, {where}"))

    data = np.full((len(rows) - 1, len(header)), np.nan)
    for i, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            problem(f"line {i}", f"{len(row)} values for {len(header)} columns")
            continue
        for j, cell in enumerate(row):
            try:
                data[i - 2, j] = float(cell)
            except ValueError:
                problem(f"line {i}, column {header[j]!r}", f"{cell.strip()!r} is not a number")
                continue
            if not math.isfinite(data[i - 2, j]):
                problem(f"line {i}, column {header[j]!r}", f"{cell.strip()} is not finite")
    if data.shape[0] < 2:
        problem("line 2", f"a motion needs at least 2 samples, got {data.shape[0]}")
    return _motion(path, header, data, problems)


def _error(path, problems: list[Problem]) -> ModelError:
    """The error of a motion file; beyond :data:`_SHOWN` problems (a file of 100,000 wrong
    columns, say), the first ones say enough and the others are counted."""
    if len(problems) > _SHOWN:
        problems = problems[:_SHOWN] + [Problem("motion", f"and {len(problems) - _SHOWN} more "
                                                "problems of the same file", str(path))]
    return ModelError(f"motion file {path}", problems)


def _motion(path: Path, header: list[str], data: np.ndarray, problems: list) -> Motion:
    """Check the columns and times of a parsed table and build the motion."""

    def problem(where: str, message: str):
        problems.append(Problem("motion", message, f"{path}, {where}"))

    if not header or header[0] != "t":
        problem("line 1", f"the first column must be 't', got {header[0]!r}")
    counts = Counter(header)  # in linear time: a file may have 100,000 columns
    for name in sorted(name for name, count in counts.items() if count > 1):
        problem("line 1", f"column {name!r} appears {_times(counts[name])}")
    if problems:
        raise _error(path, problems)
    times = data[:, 0]
    steps = np.diff(times)
    if np.any(steps <= 0):
        bad = int(np.argmax(steps <= 0)) + 3
        problem(f"line {bad}", "times must be strictly increasing")
    columns = {name: data[:, j] for j, name in enumerate(header) if j > 0}
    values, rates, accelerations = {}, {}, {}
    for name, column in columns.items():
        kind, _, joint = name.partition(":") if ":" in name else ("q", "", name)
        target = {"q": values, "qd": rates, "qdd": accelerations}.get(kind)
        if target is None or not joint:
            problem("line 1", f"column {name!r}: use '<joint>', 'qd:<joint>' or 'qdd:<joint>'")
            continue
        target[joint] = column
    for kind, table in (("qd", rates), ("qdd", accelerations)):
        for joint in table:
            if joint not in values:
                problem("line 1", f"column '{kind}:{joint}' has no column '{joint}'")
    if not values:
        problem("line 1", "no joint columns")
    if problems:
        raise _error(path, problems)
    return Motion(times, values, rates, accelerations, str(path))


def _spline_rate(t: np.ndarray, values: np.ndarray) -> tuple[np.ndarray | None, str]:
    """The derivative at the samples of the C2 spline through ``values``, or None and why the
    samples cannot be interpolated (times too close together for floating point, say)."""
    if t.size < 4:
        return np.zeros_like(t), ""
    spline = Spline(t, values)
    problems = spline.problems()
    if problems:
        return None, "; ".join(problems)
    return spline.evaluate(t)[1], ""


def _law(motion: Motion, joint: str, factor: float) -> tuple[Law | None, str]:
    """The driver law of one joint (``factor`` converts SI values to the scene's unit), or None
    and what is wrong with the samples."""
    t = motion.times
    q = motion.values[joint] * factor
    if joint in motion.rates:
        qd = motion.rates[joint] * factor
        if joint in motion.accelerations:
            qdd = motion.accelerations[joint] * factor
        else:
            qdd, trouble = _spline_rate(t, qd)
            if qdd is None:
                return None, (f"no C2 spline through the rates 'qd:{joint}' ({trouble}); "
                              f"give 'qdd:{joint}'")
        law = Hermite(t, q, qd, qdd)
    else:
        law = Spline(t, q)
    problems = law.problems()
    return (None, "; ".join(problems)) if problems else (law, "")


def _times(count: int) -> str:
    return "twice" if count == 2 else f"{count} times"


def _listed(names: list[str], limit: int = 12) -> str:
    """Names for a message, the first ``limit`` of them when there are many."""
    shown = ", ".join(names[:limit])
    return shown + (f" and {len(names) - limit} more" if len(names) > limit else "")


def _estimated(motion: Motion) -> str:
    """One warning for every joint whose derivatives are estimated rather than given ('' when
    none is): which joints, which derivatives, and how to give them."""
    both = [j for j in motion.joints if j not in motion.rates]
    second = [j for j in motion.joints if j in motion.rates and j not in motion.accelerations]
    parts = [f"{what} of {len(joints)} joint{'s' * (len(joints) > 1)} estimated by C2 "
             f"interpolating splines (columns {absent} absent): {_listed(joints)}"
             for what, absent, joints in (("velocities and accelerations", "qd: and qdd:", both),
                                          ("accelerations", "qdd:", second)) if joints]
    if not parts:
        return ""
    return (f"{motion.source or 'motion'}: {'; '.join(parts)} (give qd:<joint> and "
            "qdd:<joint> for exact derivatives)")


def _column_problems(scene: Scene, motion: Motion) -> list[tuple[str, str]]:
    """What stops each column from driving its joint: (joint, problem)."""
    joints = scene.joints
    driven = {d.joint: d.name for d in scene.drivers.values() if isinstance(d, JointDriver)}
    out = []
    for joint in motion.joints:
        if joint not in joints:
            out.append((joint, f"is not a joint of the model (joints: {_listed(list(joints))})"))
        elif not joints[joint].drivable:
            out.append((joint, f"joint '{joint}' is {joints[joint].kind}: only "
                        f"{kinds_that(lambda t: t.drivable)} joints can be driven"))
        elif joint in driven:
            out.append((joint, f"joint '{joint}' is already driven by '{driven[joint]}'"))
        elif joint not in motion.rates and motion.times.size < 4:
            out.append((joint, "a spline through the samples needs at least 4 of them (or "
                        f"give 'qd:{joint}' and 'qdd:{joint}')"))
    return out


def apply_motion(scene: Scene, motion: Motion) -> Scene:
    """A copy of ``scene`` whose joints named in ``motion`` are driven by it (driver names
    ``motion/<joint>``).

    Each law passes through the samples as the module's description says; a
    :class:`MotionWarning` names the joints whose derivatives were estimated.

    Parameters
    ----------
    scene : Scene
        The scene to drive; it is not changed.
    motion : Motion
        From :func:`read_motion`.

    Returns
    -------
    Scene

    Raises
    ------
    ModelError
        Unknown or undrivable joints, joints already driven, too few samples for a spline, or
        samples no spline passes through.
    """
    where = motion.source or "motion"

    def problem(joint: str, message: str) -> Problem:
        return Problem(f"motion column {quoted(joint)}", message, f"{where}, line 1")

    problems = [problem(joint, message) for joint, message in _column_problems(scene, motion)]
    laws = {}
    joints = scene.joints
    if not problems:
        for joint in motion.joints:
            length = joints[joint].coordinate_unit == "length"  # in metres in the file
            factor = 1.0 / scene.unit if length else 1.0
            laws[joint], trouble = _law(motion, joint, factor)
            if trouble:
                problems.append(problem(joint, trouble))
    if problems:
        raise _error(where, problems)
    # both files, so that an error of the driven model (it cannot be assembled) names them
    source = ", driven by ".join(s for s in (scene.source, motion.source) if s)
    out = scene.with_elements(
        [*scene.elements, *(JointDriver(f"motion/{joint}", joint, law,
                                        source=f"{where}, column '{joint}'")
                            for joint, law in laws.items())], source=source)
    if _estimated(motion):
        warnings.warn(_estimated(motion), MotionWarning, stacklevel=2)
    return out
