"""Joints (kinematic pairs) as descriptions: who they connect and where their frames are.

Each joint connects a **parent** (its first body) and a **child** (its second); either may be the
ground. It owns a **joint frame** fixed to the child, with its origin at the joint point; every
liaison force is reported in that frame (docs/scene-format.md, "Conventions"). The matching frame on
the parent coincides with it when the joint coordinate is zero.

The frames may be given in three ways:

* ``origin`` (and optionally ``rotation``): the joint frame in **world** coordinates at the
  initial pose, as one draws a mechanism; both body frames follow from the bodies' initial poses;
* ``child_frame``: the joint frame in the child's reference frame (a placement or a marker
  name), as URDF does; ``parent_frame`` is then derived from the initial poses unless given;
* nothing: the joint frame is the child's reference frame.

The residual rows themselves are written in :mod:`hexapod.model.joints`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hexapod.errors import Problem
from hexapod.scene.element import (
    Attachment,
    Element,
    check_axis,
    check_finite,
    check_frame,
    ground_ref,
    scaled_ref,
)
from hexapod.spatial import Placement, is_rotation


@dataclass(eq=False)
class Joint(Element):
    """Base class. See the module docstring for the frame arguments."""

    name: str
    parent: str
    child: str
    parent_frame: Placement | str | None = None
    child_frame: Placement | str | None = None
    origin: np.ndarray | None = None
    rotation: np.ndarray | None = None
    source: str = ""
    family = "joint"
    #: whether a driver or an actuator effort may act along the joint coordinate
    drivable = False
    #: the joint frame's axis along which the joint moves (a field of revolute and prismatic)
    axis = None

    def __post_init__(self):
        if self.origin is not None:
            self.origin = np.array(self.origin, dtype=float).reshape(-1)
        if self.rotation is not None:
            self.rotation = np.array(self.rotation, dtype=float)
        if self.axis is not None:
            self.axis = np.array(self.axis, dtype=float).reshape(-1)

    def problems(self) -> list[Problem]:
        out: list[Problem] = []
        if self.parent == self.child:
            out.append(self.problem("child", f"parent and child are the same ('{self.child}')"))
        check_frame(self, "parent_frame", self.parent_frame, out)
        check_frame(self, "child_frame", self.child_frame, out)
        check_finite(self, "origin", self.origin, out)
        if self.rotation is not None:
            if self.origin is None:
                out.append(self.problem("rotation", "is given without an origin"))
            if check_finite(self, "rotation", self.rotation, out) and not is_rotation(
                self.rotation
            ):
                out.append(self.problem("rotation", "is not a proper rotation matrix"))
        if self.origin is not None and (self.child_frame is not None
                                        or self.parent_frame is not None):
            out.append(self.problem("origin", "give either origin (world) or parent_frame/"
                                    "child_frame (body coordinates), not both"))
        if self.axis is not None:
            check_axis(self, "axis", self.axis, out)
        return out

    def scaled(self, length):
        out = super().scaled(length)
        out.parent_frame = scaled_ref(self.parent_frame, length)
        out.child_frame = scaled_ref(self.child_frame, length)
        out.origin = scaled_ref(self.origin, length)
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        out.parent = attachment.body(self.parent)
        out.child = attachment.body(self.child)
        out.parent_frame = ground_ref(self.parent_frame, self.parent, attachment)
        out.child_frame = ground_ref(self.child_frame, self.child, attachment)
        if self.origin is not None:
            T = attachment.transform
            out.origin = T.transform_point(self.origin)
            out.rotation = T.rotation @ (np.eye(T.dimension) if self.rotation is None
                                         else self.rotation)
        return out


def _axis_default(joint: Joint, default) -> None:
    joint.axis = np.array(default if joint.axis is None else joint.axis, dtype=float).reshape(-1)


@dataclass(eq=False)
class Revolute(Joint):
    """One rotation about ``axis`` (in the joint frame; default z). 5 rows in space, 2 in the plane
    (where the axis is always normal to the plane). The joint angle is measured from the parent
    frame to the child frame, positive about the axis."""

    axis: np.ndarray | None = None
    kind = "revolute"
    drivable = True

    def __post_init__(self):
        _axis_default(self, (0.0, 0.0, 1.0))
        super().__post_init__()


@dataclass(eq=False)
class Prismatic(Joint):
    """One translation along ``axis`` (in the joint frame; default x in the plane, z in space).
    5 rows in space, 2 in the plane. The displacement is that of the child frame's origin from
    the parent frame's origin, along the axis."""

    axis: np.ndarray | None = None
    kind = "prismatic"
    drivable = True


@dataclass(eq=False)
class Spherical(Joint):
    """A ball joint: the two frame origins coincide (3 rows). Space only (in the plane it would
    be a revolute joint)."""

    kind = "spherical"


@dataclass(eq=False)
class Fixed(Joint):
    """A weld: no relative motion (6 rows in space, 3 in the plane)."""

    kind = "fixed"


@dataclass(eq=False)
class Distance(Joint):
    """A rigid link between the parent frame's origin and the child frame's origin (1 row).

    ``length`` defaults to the distance at the initial pose; the rods of Richard, Anderson and
    Andrews (1989/90) are distance joints between particles.
    """

    length: float | None = None
    kind = "distance"

    def problems(self):
        out = super().problems()
        if self.length is not None and check_finite(self, "length", self.length, out) and (
            not self.length > 0
        ):
            out.append(self.problem("length", f"must be positive, got {self.length}"))
        return out

    def scaled(self, length):
        out = super().scaled(length)
        if self.length is not None:
            out.length = self.length * length
        return out


@dataclass(eq=False)
class Universal(Joint):
    """A Cardan joint: rotations about ``axis`` (fixed to the parent, default x) and ``axis2``
    (fixed to the child, default y), both given in the joint frame and perpendicular. The two
    frame origins coincide: 4 rows. Space only."""

    axis: np.ndarray | None = None
    axis2: np.ndarray | None = None
    kind = "universal"

    def __post_init__(self):
        _axis_default(self, (1.0, 0.0, 0.0))
        self.axis2 = np.array((0.0, 1.0, 0.0) if self.axis2 is None else self.axis2,
                              dtype=float).reshape(-1)
        super().__post_init__()

    def problems(self):
        out = super().problems()
        check_axis(self, "axis2", self.axis2, out)
        if not out and self.axis.size == self.axis2.size == 3:
            cosine = self.axis @ self.axis2 / np.linalg.norm(self.axis) / np.linalg.norm(
                self.axis2)
            if abs(cosine) > 1e-9:
                out.append(self.problem("axis2", f"must be perpendicular to axis (cosine "
                                        f"{cosine:.3g})"))
        return out


@dataclass(eq=False)
class Cylindrical(Joint):
    """Rotation about and translation along ``axis`` (joint frame; default z): 4 rows in space.
    In the plane it is a pin in a slot along ``axis`` (default x): the child frame's origin
    stays on the parent's line, and the child may turn (1 row)."""

    axis: np.ndarray | None = None
    kind = "cylindrical"


@dataclass(eq=False)
class PlanarJoint(Joint):
    """The child frame slides and turns in the plane of the parent frame whose normal is
    ``axis`` (joint frame; default z): two translations and a rotation, 3 rows. Space only."""

    axis: np.ndarray | None = None
    kind = "planar"


@dataclass(eq=False)
class PointOnPlane(Joint):
    """The child frame's origin stays on the plane through the parent frame's origin with
    normal ``axis`` (joint frame on the parent; default z, or y in the plane, where the plane is
    a line): a foot on the ground. 1 row; the child may be a particle."""

    axis: np.ndarray | None = None
    kind = "point-on-plane"


@dataclass(eq=False)
class Contact(Joint):
    """A foot on the ground by a gait's schedule: while the foot is in **stance** its point (the
    child frame's origin) stays at its **foothold** (3 rows, world axes: no slip); in **swing**
    the rows vanish. The parent is the ground, whose normal is world ``z``.

    The schedule repeats every ``period`` (s): the foot lifts off at ``lift_off`` (a fraction of
    the period) and is on the ground for the fraction ``duty`` before that, so stance ``k``
    lasts from ``(lift_off + k - duty) period`` to ``(lift_off + k) period``. Its foothold is
    ``foothold + k advance`` (world, scene units): ``foothold`` is where the foot stands in the
    stance that ends at ``t = lift_off period``, ``advance`` how far the footholds move each
    cycle (the stride, for a robot walking straight).

    A foot's share of the ground forces grows from zero at touch-down and falls to zero at
    lift-off over ``ramp`` (a fraction of the stance), so the forces are continuous in time
    (:mod:`hexapod.scene.contacts`).
    """

    period: float = 1.0
    duty: float = 0.5
    lift_off: float = 0.0
    foothold: np.ndarray | None = None
    advance: np.ndarray | None = None
    ramp: float = 0.1
    kind = "contact"

    def __post_init__(self):
        super().__post_init__()
        self.foothold = np.zeros(3) if self.foothold is None else np.array(
            self.foothold, dtype=float).reshape(-1)
        self.advance = np.zeros(3) if self.advance is None else np.array(
            self.advance, dtype=float).reshape(-1)

    def problems(self):
        out = super().problems()
        if self.parent != "ground":
            out.append(self.problem("parent", f"a contact's parent is the ground, got "
                                    f"'{self.parent}'"))
        for key in ("foothold", "advance"):
            value = getattr(self, key)
            if check_finite(self, key, value, out) and value.size != 3:
                out.append(self.problem(key, f"needs 3 numbers, got {value.size}"))
        numbers = {k: getattr(self, k) for k in ("period", "duty", "lift_off", "ramp")}
        if not all(check_finite(self, k, v, out) for k, v in numbers.items()):
            return out
        if not self.period > 0:
            out.append(self.problem("period", f"must be positive, got {self.period}"))
        if not 0 < self.duty <= 1:
            out.append(self.problem("duty", f"must be in (0, 1], got {self.duty}"))
        if not 0 <= self.lift_off < 1:
            out.append(self.problem("lift_off", f"must be in [0, 1), got {self.lift_off}"))
        if not 0 < self.ramp <= 0.5:
            out.append(self.problem("ramp", f"must be in (0, 0.5], got {self.ramp}"))
        return out

    def scaled(self, length):
        out = super().scaled(length)
        out.foothold = self.foothold * length
        out.advance = self.advance * length
        return out

    def attached(self, attachment: Attachment):
        out = super().attached(attachment)
        if attachment.base != "ground":  # footholds are in the world
            out.parent = "ground"
        T = attachment.transform
        out.foothold = T.transform_point(self.foothold)
        out.advance = T.rotation @ self.advance
        return out


#: Joint classes by the ``type`` used in scene files.
JOINT_TYPES: dict[str, type[Joint]] = {
    cls.kind: cls for cls in (Revolute, Prismatic, Spherical, Fixed, Distance, Universal,
                              Cylindrical, PlanarJoint, PointOnPlane, Contact)
}

#: Joints that exist in a planar scene.
PLANE_JOINTS = frozenset({"revolute", "prismatic", "fixed", "distance", "cylindrical",
                          "point-on-plane"})

#: Joints whose parent (p) or child (c) may be a particle, in space (3) and in the plane (2).
PARTICLE_ENDS = {
    3: {"spherical": "pc", "distance": "pc", "point-on-plane": "c"},
    2: {"revolute": "pc", "distance": "pc", "cylindrical": "c", "point-on-plane": "c"},
}
