"""The one exception family of hexapod.

Every error a user can cause is a :class:`HexapodError`; its message names the file (when there is
one), the element and what is wrong. Misuse of the API by a programmer (wrong types, wrong shapes)
may raise the usual ``TypeError`` / ``ValueError``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np


class HexapodError(Exception):
    """Base class of every error raised for bad input or a failed computation."""


@dataclass(frozen=True)
class Problem:
    """One problem found in a scene description.

    Attributes
    ----------
    element : str
        What the problem is about, e.g. ``"body 'femur'"`` or ``"scene"``.
    message : str
        What is wrong, with the offending value.
    where : str
        Where it was written, e.g. ``"leg.toml, body[2].mass"``; empty for scenes built in Python.
    """

    element: str
    message: str
    where: str = ""

    def __str__(self) -> str:
        location = f" ({self.where})" if self.where else ""
        return f"{self.element}{location}: {self.message}"


class ModelError(HexapodError):
    """A scene description is invalid. Carries every problem found, not only the first.

    Parameters
    ----------
    subject : str
        What was checked, e.g. ``"scene file leg.toml"``; the message's first line.
    problems : list of Problem
        Every problem found, one line each in the message.
    """

    def __init__(self, subject: str, problems: list[Problem]):
        self.subject = subject
        self.problems = list(problems)
        count = len(self.problems)
        head = f"{subject}: {count} problem{'s' if count != 1 else ''}"
        super().__init__(head + "".join(f"\n  - {p}" for p in self.problems))


class InputFileError(HexapodError):
    """A file cannot be read or parsed (missing, syntax error, wrong structure)."""


class AssemblyError(HexapodError):
    """No configuration satisfies the constraints from the given guess.

    Parameters
    ----------
    message : str
        What failed, where.
    time : float, optional
        The time at which Newton's method stalled, s, when it did.
    positions : ndarray, optional
        Where it stalled (n_q), when it did: a start for finding which constraints cannot be
        met together.
    """

    def __init__(self, message: str, time: float | None = None,
                 positions: np.ndarray | None = None):
        super().__init__(message)
        self.time, self.positions = time, positions


class SingularSystemError(HexapodError):
    """The equations of motion have no unique solution (e.g. inconsistent constraints)."""


class IntegrationError(HexapodError):
    """A time integration cannot proceed."""


class JointLimitError(HexapodError):
    """A motion takes a joint out of its range (its ``limits``: a scene file's, or a URDF's
    ``<limit>``).

    Parameters
    ----------
    message : str
        The message: the model, the joint, the time, the value and the range.
    joint : str
        The joint that leaves its range first (the earliest sample; of two at once, the first
        in the model's order).
    time : float
        The first sample outside, s.
    value : float
        The joint's coordinate there, rad or m.
    limits : tuple of float
        Its range ``(lower, upper)``, rad or m.
    """

    def __init__(self, message: str, joint: str, time: float, value: float,
                 limits: tuple[float, float]):
        super().__init__(message)
        self.joint, self.time, self.value, self.limits = joint, time, value, limits
