"""Drivers: rheonomic constraint rows that prescribe a joint coordinate or a body coordinate.

A driver on a revolute joint prescribes its angle with the **wrapped** row
``atan2(sin(theta - f), cos(theta - f))`` (correct past +-pi); on a prismatic joint its
displacement, ``s - f``. A coordinate driver prescribes one coordinate of a body's centre of mass
(``x``, ``y``, ``z``) or, in the plane, its ``angle``. Laws must be C2 (see :mod:`.laws`).
"""

from __future__ import annotations

from dataclasses import dataclass

from hexapod.scene.element import Attachment, Element
from hexapod.scene.laws import Law, LawOnJoint, as_law

#: coordinates a :class:`CoordinateDriver` may prescribe
COORDINATES = ("x", "y", "z", "angle")


@dataclass(eq=False)
class JointDriver(LawOnJoint, Element):
    """Prescribes the coordinate of a revolute (rad) or prismatic (L) joint by ``law``.

    Parameters
    ----------
    name : str
        The driver's name, unique among the drivers.
    joint : str
        The driven joint (a type with a coordinate: revolute, prismatic).
    law : Law or float
        The coordinate as a function of time (rad or L), C2 at least; a number is a
        :class:`~hexapod.scene.laws.Constant`.
    source : str
        Where the driver was written, named in messages; empty when built in Python.
    """

    name: str
    joint: str
    law: Law
    source: str = ""
    family = "driver"
    kind = "joint"


@dataclass(eq=False)
class CoordinateDriver(Element):
    """Prescribes ``coordinate`` (``x``, ``y``, ``z`` of the centre of mass, or the planar
    ``angle``) of ``body`` by ``law``, in world axes.

    Parameters
    ----------
    name : str
        The driver's name, unique among the drivers.
    body : str
        The driven body.
    coordinate : {"x", "y", "z", "angle"}
        Which coordinate of its centre of mass (world axes), or its planar angle.
    law : Law or float
        The coordinate as a function of time (L, or rad for ``angle``), C2 at least.
    source : str
        Where the driver was written, named in messages; empty when built in Python.
    """

    name: str
    body: str
    coordinate: str
    law: Law
    source: str = ""
    family = "driver"
    kind = "coordinate"

    def __post_init__(self):
        self.law = as_law(self.law)

    def problems(self):
        out = [self.problem("law", message) for message in self.law.problems()]
        if self.coordinate not in COORDINATES:
            out.append(self.problem("coordinate", f"must be one of {', '.join(COORDINATES)},"
                                    f" got {self.coordinate!r}"))
        return out

    def scaled(self, length):
        out = super().scaled(length)
        if self.coordinate != "angle":
            out.law = self.law.scaled(length)
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        out.body = attachment.body(self.body)
        return out


DRIVER_TYPES: dict[str, type[Element]] = {"joint": JointDriver, "coordinate": CoordinateDriver}
