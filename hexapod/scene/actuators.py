"""Actuators: the motors behind a scene's driven joints, read from an actuator table.

An actuator is a DC motor behind an ideal gear of ratio ``N`` (motor turns per joint turn, or
motor radians per metre for a prismatic joint). Its numbers are the motor's, at its shaft:

* the torque-speed envelope, either the motor's **stall torque** ``tau_s`` and **no-load
  speed** ``w_0`` (a DC motor at its supply voltage: ``|tau_m / tau_s + w_m / w_0| <= 1``,
  the line ``tau_m = tau_s (1 - w_m / w_0)`` where it drives the motion, more torque where the
  motion drives it), or a **rated torque** and **rated speed** (``|tau_m| <= tau_r``,
  ``|w_m| <= w_r``);
* optionally the **torque constant** ``k_t`` (N m/A, equal to the back-EMF constant in SI
  units) and the **winding resistance** ``R`` (ohm), which give the current
  ``I = tau_m / k_t`` and the electrical power ``tau_m w_m + R I^2``.

At the joint, ``tau = N tau_m`` and ``w = w_m / N``: the envelope is the joint controller's
(:class:`hexapod.scene.forces.JointController`, its ``max_effort = N tau_s`` and
``no_load_speed = w_0 / N``), by the same :func:`effort_limits`.

The table is a TOML file of ``[[actuator]]`` entries, each naming the joints it drives by name
or by shell-style pattern (``"*/ctr"``: every leg's ``ctr``); the format is in
``docs/report.md``.
"""

from __future__ import annotations

import fnmatch
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from hexapod._support.files import read_toml
from hexapod.errors import InputFileError

if TYPE_CHECKING:
    import casadi as ca
    import numpy as np

#: the keys of an ``[[actuator]]`` entry and what each must be
KEYS = {"name": "a string", "joints": "a list of joint names or patterns",
        "gear_ratio": "a positive number", "stall_torque": "a positive number",
        "no_load_speed": "a positive number", "rated_torque": "a positive number",
        "rated_speed": "a positive number", "torque_constant": "a positive number",
        "resistance": "a non-negative number"}


@dataclass(frozen=True)
class Actuator:
    """A motor and its gear (see the module's description); numbers at the motor's shaft, SI.

    Attributes
    ----------
    name : str
        Shown in the report.
    joints : tuple of str
        The joints it drives: names or shell-style patterns.
    gear_ratio : float
        Motor speed over joint speed.
    stall_torque, no_load_speed : float or None
        The DC motor's envelope (N m, rad/s), both or neither.
    rated_torque, rated_speed : float or None
        A rectangular envelope instead (N m, rad/s), both or neither.
    torque_constant, resistance : float or None
        For the current and the electrical power (N m/A, ohm), both or neither.
    """

    name: str
    joints: tuple[str, ...]
    gear_ratio: float = 1.0
    stall_torque: float | None = None
    no_load_speed: float | None = None
    rated_torque: float | None = None
    rated_speed: float | None = None
    torque_constant: float | None = None
    resistance: float | None = None

    @property
    def electrical(self) -> bool:
        """Whether the current and the electrical power can be computed."""
        return self.torque_constant is not None

    def joint_limits(self) -> tuple[float, float | None, float | None]:
        """The envelope at the joint: ``(max_effort, no_load_speed, rated_speed)``, the last
        two None where the envelope has no such limit."""
        N = self.gear_ratio
        if self.stall_torque is not None:
            return N * self.stall_torque, self.no_load_speed / N, None
        return N * self.rated_torque, None, self.rated_speed / N


def effort_limits(max_effort: float, no_load_speed: float | None,
                  rate: np.ndarray | ca.SX) -> tuple:
    """The effort range ``(lower, upper)`` of an actuator at joint speed ``rate``:
    ``+-max_effort``, and with ``no_load_speed`` (not None) the DC motor's torque-speed line,
    ``-max_effort (1 + w / w0) <= tau <= max_effort (1 - w / w0)``. Works on NumPy arrays and
    on CasADi expressions alike (the joint controller's clipping).

    Parameters
    ----------
    max_effort : float
        The stall effort at the joint (N m or N), positive.
    no_load_speed : float or None
        The joint speed where the effort in the direction of motion falls to zero.
    rate : ndarray or casadi.SX
        The joint speed.

    Returns
    -------
    tuple
        ``(lower, upper)``, as ``rate``.
    """
    upper, lower = max_effort + 0 * rate, -max_effort + 0 * rate
    if no_load_speed is not None:
        upper = max_effort * (1 - rate / no_load_speed)
        lower = -max_effort * (1 + rate / no_load_speed)
    return lower, upper


@dataclass(frozen=True)
class ActuatorTable:
    """The actuators of a table and where they were read.

    Attributes
    ----------
    actuators : tuple of Actuator
        In the table's order.
    source : str
        The file (named in the report and in messages).
    """

    actuators: tuple[Actuator, ...]
    source: str

    def assign(self, joints: list[str]) -> dict[str, Actuator]:
        """Which actuator drives each of ``joints`` (see :func:`assign`)."""
        return assign(self.actuators, joints, self.source)


def read_actuators(path: str | Path) -> ActuatorTable:
    """Read an actuator table (TOML, ``[[actuator]]`` entries; see the module's description).

    Parameters
    ----------
    path : str or Path
        The file.

    Returns
    -------
    ActuatorTable
        Its actuators in the file's order.

    Raises
    ------
    InputFileError
        The file cannot be read, is not TOML, or an entry is wrong: every problem in one
        message, each naming the file, the entry and the key.
    """
    path = Path(path)
    document = read_toml(path, "actuator table")
    entries = document.get("actuator")
    problems = [f"unknown key '{key}' (expected [[actuator]] entries)"
                for key in document if key != "actuator"]
    if not isinstance(entries, list) or not entries or not all(
            isinstance(e, dict) for e in entries):
        problems.append("no [[actuator]] entries")
        entries = []
    actuators = []
    for k, entry in enumerate(entries):
        where = f"actuator {k + 1}" + (f" ('{entry['name']}')" if isinstance(
            entry.get("name"), str) else "")
        found = _entry_problems(entry)
        problems += [f"{where}: {p}" for p in found]
        if not found:
            numbers = {key: float(value) for key, value in entry.items()
                       if key not in ("name", "joints")}
            actuators.append(Actuator(entry.get("name", f"actuator {k + 1}"),
                                      tuple(entry["joints"]), **numbers))
    if problems:
        raise InputFileError(f"{path}: " + "; ".join(problems))
    return ActuatorTable(tuple(actuators), str(path))


def _entry_problems(entry: dict) -> list[str]:
    """What is wrong with one ``[[actuator]]`` entry."""
    out = [f"unknown key '{key}' (known: {', '.join(KEYS)})" for key in entry if key not in KEYS]
    joints = entry.get("joints")
    if not (isinstance(joints, list) and joints and all(
            isinstance(j, str) and j for j in joints)):
        out.append(f"joints must be {KEYS['joints']}, got {joints!r}")
    if "name" in entry and not isinstance(entry["name"], str):
        out.append(f"name must be a string, got {entry['name']!r}")
    for key, value in entry.items():
        if key in ("name", "joints") or key not in KEYS:
            continue
        ok = (isinstance(value, int | float) and not isinstance(value, bool)
              and math.isfinite(value) and (value >= 0 if key == "resistance" else value > 0))
        if not ok:
            out.append(f"{key} must be {KEYS[key]}, got {value!r}")
    pairs = (("stall_torque", "no_load_speed"), ("rated_torque", "rated_speed"),
             ("torque_constant", "resistance"))
    for a, b in pairs:
        if (a in entry) != (b in entry):
            out.append(f"{a} and {b} go together: give both or neither")
    motor, rated = "stall_torque" in entry, "rated_torque" in entry
    if motor == rated:
        out.append("give the envelope as stall_torque and no_load_speed, or as rated_torque and "
                   "rated_speed" + (" (not both)" if motor else ""))
    return out


def assign(actuators: tuple[Actuator, ...], joints: list[str],
           source: str = "the actuator table") -> dict[str, Actuator]:
    """Which actuator drives each of ``joints`` (the driven joints' names).

    Parameters
    ----------
    actuators : tuple of Actuator
    joints : list of str
        The driven joints.
    source : str
        Names the table in messages.

    Returns
    -------
    dict of str to Actuator
        By joint name; a joint no entry names is left out (not checked).

    Raises
    ------
    InputFileError
        An entry's pattern matches no driven joint, or a joint is matched by two entries.
    """
    out: dict[str, Actuator] = {}
    problems = []
    for actuator in actuators:
        for pattern in actuator.joints:
            matched = [j for j in joints if fnmatch.fnmatchcase(j, pattern)]
            if not matched:
                problems.append(f"{actuator.name}: '{pattern}' names no driven joint "
                                f"(driven: {', '.join(joints) or 'none'})")
            for joint in matched:
                if joint in out and out[joint] is not actuator:
                    problems.append(f"joint '{joint}' is driven by both {out[joint].name} and "
                                    f"{actuator.name}")
                out[joint] = actuator
    if problems:
        raise InputFileError(f"{source}: " + "; ".join(dict.fromkeys(problems)))
    return out
