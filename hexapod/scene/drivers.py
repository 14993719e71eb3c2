"""Drivers: rheonomic constraint rows that prescribe a joint coordinate or a body coordinate.

A driver on a revolute joint prescribes its angle with the **wrapped** row
``atan2(sin(theta - f), cos(theta - f))`` (correct past +-pi); on a prismatic joint its
displacement, ``s - f``. A coordinate driver prescribes one coordinate of a body point (``x``,
``y``, ``z``: of its centre of mass by default, in world axes or in another body's frame) or, in
the plane, the body's ``angle``. Laws must be C2 (see :mod:`.laws`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from hexapod.errors import ModelError, Problem
from hexapod.scene.element import (
    GROUND,
    Attachment,
    Element,
    check_finite,
    quoted,
    scaled_ref,
)
from hexapod.scene.laws import Guided, Law, LawOnJoint, as_law

#: coordinates a :class:`CoordinateDriver` may prescribe
COORDINATES = ("x", "y", "z", "angle", "roll", "pitch", "yaw")
#: the angles among them: a spatial body's Tait-Bryan angles (z-y-x: yaw, then pitch, then
#: roll), and a planar body's angle
ORIENTATIONS = ("roll", "pitch", "yaw")


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
    """Prescribes ``coordinate`` (``x``, ``y``, ``z``) of a point of ``body`` by ``law``: of its
    centre of mass in world axes by default, of another ``point``, and in the axes of another
    body's reference frame (``frame``, relative to that frame's origin); or one angle of the
    body's reference axes: in space its ``roll``, ``pitch`` or ``yaw`` (Tait-Bryan z-y-x, the
    rotation ``Rz(yaw) Ry(pitch) Rx(roll)`` from ``frame``'s axes; singular at a pitch of
    +-90 degrees), in the plane its ``angle``.

    Three coordinate drivers on a foot point, in the trunk's frame, are how a foot follows a
    path: the engine's Newton solve then finds the joint angles that put it there, for any leg.

    Parameters
    ----------
    name : str
        The driver's name, unique among the drivers.
    body : str
        The driven body.
    coordinate : {"x", "y", "z", "angle", "roll", "pitch", "yaw"}
        Which coordinate of the point (along ``frame``'s axes), or which angle.
    law : Law or float
        The coordinate as a function of time (L, or rad for an angle), C2 at least.
    source : str
        Where the driver was written, named in messages; empty when built in Python.
    point : str or array_like, optional
        The driven point: a marker name or a point in the body's reference frame (L); default
        the centre of mass.
    frame : str
        ``world``, or the body in whose reference frame the coordinate is measured (along its
        axes, from its origin).
    guide : bool
        A guide prescribes the motion but exerts no force: in the inverse dynamics the joints
        whose drivers follow the guides (law :class:`~hexapod.scene.laws.Guided`) carry the
        efforts instead (see :mod:`hexapod.scene.laws.guided`).
    """

    name: str
    body: str
    coordinate: str
    law: Law
    source: str = ""
    point: object = None
    frame: str = "world"
    guide: bool = False
    family = "driver"
    kind = "coordinate"

    def __post_init__(self):
        self.law = as_law(self.law)

    def problems(self):
        out = [self.problem("law", message) for message in self.law.problems()]
        if self.coordinate not in COORDINATES:
            out.append(self.problem("coordinate", f"must be one of {', '.join(COORDINATES)},"
                                    f" got {self.coordinate!r}"))
        if self.coordinate == "angle" and (self.point is not None or self.frame != "world"):
            out.append(self.problem("coordinate", "an angle is the body's, in world axes: "
                                    "drop 'point' and 'frame', or drive x, y or z"))
        if self.coordinate in ORIENTATIONS and self.point is not None:
            out.append(self.problem("point", f"a {self.coordinate} angle is the body's "
                                    "orientation, not a point's: drop 'point'"))
        if self.point is not None and not isinstance(self.point, str):
            check_finite(self, "point", self.point, out)
        if self.frame == self.body:
            out.append(self.problem("frame", f"'{self.body}' cannot be measured in its own "
                                    "frame: name another body, or 'world'"))
        return out

    def scaled(self, length):
        out = super().scaled(length)
        if self.coordinate in ("x", "y", "z"):
            out.law = self.law.scaled(length)
        out.point = scaled_ref(self.point, length)
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        out.body = attachment.body(self.body)
        placement = attachment.placement
        if self.frame == GROUND and not (np.all(placement.position == 0)
                                         and np.array_equal(placement.rotation,
                                                            np.eye(placement.dimension))):
            raise ModelError(self.label, [self.problem(
                "frame", f"measured in the sub-model's ground, which is attached at a placed "
                f"frame of '{attachment.base}': measure it in a body of the sub-model")])
        if self.frame != "world":
            out.frame = attachment.body(self.frame)
        return out


@dataclass(eq=False)
class PostureDriver(Element):
    """The rule that resolves a leg with more joints than its foot's guides need: of the
    joint coordinates that put the foot where its three guides say, the one nearest the rest
    posture, weighted (the least ``sum w_i (theta_i - rest_i)^2`` over ``joints``).

    It serves the guides' kinematics only (:mod:`hexapod.scene.laws.guided`; it exerts no
    force). Its rows are the optimality conditions, one per joint beyond three: with ``G``
    the foot point's velocity per joint rate (columns ``a_i x (r - p_i)``, joint ``i``'s
    world axis ``a_i`` through ``p_i``, ``r`` the foot point), the weighted
    offsets ``w_i (theta_i - rest_i)`` have no component along the null space of ``G``,
    spanned by one vector per extra joint from the three joints whose columns are best
    conditioned at the initial pose (Cramer's rule: :mod:`hexapod.model.assemble`). The
    solution is continuous in time while those three columns stay independent.

    Parameters
    ----------
    name : str
        The driver's name, unique among the drivers.
    body : str
        The foot's body: the guides' driven body.
    joints : tuple of str
        The leg's revolute joints, more than three, each following the guides (law
        ``guided``).
    rest : array_like
        Each joint's rest angle, rad.
    weights : array_like, optional
        Each joint's weight, positive; default all 1.
    point : str or array_like, optional
        The foot point (a marker or a point in the body's reference frame, L); default the
        centre of mass.
    source : str
        Where the driver was written, named in messages; empty when built in Python.
    """

    name: str
    body: str
    joints: tuple
    rest: np.ndarray
    weights: np.ndarray | None = None
    point: object = None
    source: str = ""
    family = "driver"
    kind = "posture"

    def __post_init__(self):
        self.joints = tuple(self.joints)
        self.rest = np.array(self.rest, dtype=float).reshape(-1)
        self.weights = (np.ones(len(self.joints)) if self.weights is None
                        else np.array(self.weights, dtype=float).reshape(-1))

    def problems(self):
        out = []
        if len(self.joints) < 4 or not all(isinstance(j, str) for j in self.joints):
            out.append(self.problem("joints", "needs the names of more than three joints (the "
                                    "foot's three guides decide three)"))
        for key in ("rest", "weights"):
            value = getattr(self, key)
            if check_finite(self, key, value, out) and value.size != len(self.joints):
                out.append(self.problem(key, f"needs {len(self.joints)} numbers, one per "
                                        f"joint, got {value.size}"))
        if np.all(np.isfinite(self.weights)) and not np.all(self.weights > 0):
            out.append(self.problem("weights", "must be positive"))
        if self.point is not None and not isinstance(self.point, str):
            check_finite(self, "point", self.point, out)
        return out

    def scaled(self, length):
        out = super().scaled(length)
        out.point = scaled_ref(self.point, length)
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        out.body = attachment.body(self.body)
        out.joints = tuple(attachment.name(j) for j in self.joints)
        return out


def guidance_problems(elements, scene_problem) -> list[Problem]:
    """Guides (coordinate drivers with ``guide``) and the joint drivers that follow them (law
    :class:`~hexapod.scene.laws.Guided`) come together, and nothing else follows them; a
    posture rule needs guides.
    ``scene_problem(key, message)`` makes a problem of the scene's own."""
    out, guides, guided, postures = [], [], [], []
    for e in elements:
        for f in dataclasses.fields(e):
            value = getattr(e, f.name)
            if isinstance(value, Guided) or (isinstance(value, tuple) and any(
                    isinstance(x, Guided) for x in value)):
                if isinstance(e, JointDriver) and f.name == "law":
                    guided.append(e.name)
                else:
                    out.append(e.problem(f.name, "only a joint driver's law may be 'guided' "
                                         "(its joint then follows the guides)"))
        if isinstance(e, CoordinateDriver) and e.guide:
            guides.append(e.name)
        if isinstance(e, PostureDriver):
            postures.append(e.name)
    if guides and not guided:
        out.append(scene_problem(
            "driver", f"guide(s) {', '.join(map(quoted, guides))} exert no force, but no joint "
            "driver follows them: give the joints that carry their load the law "
            "{ type = \"guided\" }"))
    if guided and not guides:
        out.append(scene_problem(
            "driver", f"joint driver(s) {', '.join(map(quoted, guided))} follow the guides, "
            "but the scene has none: mark the coordinate drivers that prescribe the motion "
            "with guide = true"))
    if postures and not guides:
        out.append(scene_problem(
            "driver", f"posture rule(s) {', '.join(map(quoted, postures))} choose among the "
            "poses the guides allow, but the scene has no guides"))
    return out


DRIVER_TYPES: dict[str, type[Element]] = {"joint": JointDriver, "coordinate": CoordinateDriver,
                                          "posture": PostureDriver}
