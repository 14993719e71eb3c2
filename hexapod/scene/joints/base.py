"""The joint base class: what every joint type answers, and the registry of the types.

Each joint connects a **parent** (its first body) and a **child** (its second); either may be the
ground. It owns a **joint frame** fixed to the child, with its origin at the joint point; every
liaison force is reported in that frame (docs/scene-format.md, "Conventions"). The matching frame
on the parent coincides with it when the joint coordinate is zero.

The frames may be given in three ways:

* ``origin`` (and optionally ``rotation``): the joint frame in **world** coordinates at the
  initial pose, as one draws a mechanism; both body frames follow from the bodies' initial poses;
* ``child_frame``: the joint frame in the child's reference frame (a placement or a marker
  name), as URDF does; ``parent_frame`` is then derived from the initial poses unless given;
* nothing: the joint frame is the child's reference frame.

A joint type is one subclass, registered with :func:`register` under the ``type`` scene files
use. It answers every question the scene's checks, the files, the assembly and the algorithms
ask about a joint (the Pinocchio and SymPy way: no code elsewhere switches on a type's name):

=========================  =====================================================================
``file_keys(dimension)``   the keys of a scene file beyond the common ones, and their values
``unit_axis(dimension)``   its unit axis in the joint frame (``default_axis`` when not given)
``exists_in_plane``        whether it exists in a planar scene; ``plane_hint`` what to use there
``particle_ends``          per dimension, which ends may be particles: ``p`` parent, ``c`` child
``joins_two_points``       its frames are two points apart (each defaults to its body's origin)
``rows(g, laws)``          its constraint rows (:class:`~.geometry.JointGeometry`, CasADi)
``drivable``               whether a driver or an actuator effort acts on its coordinate
``coordinate_unit``        the coordinate's unit kind (``angle``, ``length``); ``effort_unit``
``driver_row(g, f)``       the driver's residual for the law value ``f``
``rate(g, q, qdot)``       the coordinate's rate (the power-conjugate of its effort)
``twist(dimension)``       its motion per unit coordinate rate: (linear, angular), joint frame
``effort(force, torque)``  that twist dotted with a wrench in the joint frame
``tree_step(value)``       the child frame on the parent's for a coordinate value (tree path)
``turns``                  whether it has an angle about its axis (for a torsion spring)
``urdf_types``             its types in URDF files (the first is written), when URDF has it
``limits``                 the range of its coordinate, when given (a field of the types whose
                           ``file_keys`` hold it: revolute and prismatic joints)
=========================  =====================================================================
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

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
from hexapod.scene.joints.geometry import LENGTH, JointGeometry, Row, embedded
from hexapod.spatial import Placement, is_rotation

#: the kinds of value a scene file's joint key takes (see :meth:`Joint.file_keys`): a number,
#: as many numbers as the scene has dimensions, three numbers, two numbers
NUMBER, VECTOR, VECTOR3, PAIR = "number", "vector", "vector3", "pair"
#: an optional key holding an axis
AXIS = (VECTOR, False)
#: an optional key holding the range of the joint's coordinate, ``[lower, upper]``
LIMITS = (PAIR, False)


class LawSymbols(Protocol):
    """Where a joint's rows get the symbols of the time laws they depend on (the assembly's laws:
    a contact's stance gate and footholds)."""

    def value(self, law: Any, label: str, where: tuple) -> tuple[Any, int]:
        """The law's value as a CasADi expression and its index among the model's laws."""


@dataclass(eq=False)
class Joint(Element):
    """Base class of the joint types. See the module docstring for the frame arguments and for
    what a type answers.

    Parameters
    ----------
    name : str
        The joint's name, unique among the joints.
    parent, child : str
        The names of its first and second bodies (``"ground"`` for the fixed frame); the joint
        frame is fixed to the child, and its wrench is the parent's on the child.
    parent_frame, child_frame : Placement or str, optional
        The joint frame in the parent's and in the child's reference frame (L), or the name of
        a marker of that body. Not with ``origin``.
    origin : array_like, shape (3,) or (2,), optional
        The joint frame's origin in world coordinates at the initial pose (L).
    rotation : array_like, shape (3, 3), optional
        The joint frame's axes in world coordinates at the initial pose (joint -> world), with
        ``origin``; default: the world's axes.
    source : str
        Where the joint was written (file and entry), named in messages; empty for a joint
        built in Python.

    L is the scene's length unit (:attr:`Scene.length_unit`).
    """

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
    drivable: ClassVar[bool] = False
    #: the joint frame's axis along which the joint moves (a field of the types that have one)
    axis = None
    #: ``[lower, upper]``, the range of the joint's coordinate (rad, or L for a length), which
    #: the inverse dynamics checks a motion against; None: no range (a field of the types
    #: that have one)
    limits = None
    #: per dimension in which the joint has an axis, its default (joint frame)
    default_axis: ClassVar[dict[int, tuple[float, ...]]] = {}
    #: whether the joint exists in a planar scene, and what to use there instead
    exists_in_plane: ClassVar[bool] = False
    plane_hint: ClassVar[str] = ""
    #: per dimension, the ends that may be particles: "p" (parent), "c" (child)
    particle_ends: ClassVar[dict[int, str]] = {}
    #: whether the two frames are two points apart (each then defaults to its body's origin)
    joins_two_points: ClassVar[bool] = False
    #: whether it has an angle about its axis (a torsion spring's)
    turns: ClassVar[bool] = False
    #: unit kinds of the coordinate ("angle" or "length") and of its effort ("N m" or "N")
    coordinate_unit: ClassVar[str | None] = None
    effort_unit: ClassVar[str | None] = None
    #: its types in URDF files, the first the one written (none: URDF has no such joint)
    urdf_types: ClassVar[tuple[str, ...]] = ()
    #: ``tree_step(value)`` of the types the tree path of the inverse dynamics follows (None:
    #: it does not follow this type)
    tree_step: ClassVar[Callable | None] = None

    def __post_init__(self):
        if self.origin is not None:
            self.origin = np.array(self.origin, dtype=float).reshape(-1)
        if self.rotation is not None:
            self.rotation = np.array(self.rotation, dtype=float)
        if self.axis is not None:
            self.axis = np.array(self.axis, dtype=float).reshape(-1)
        if self.limits is not None:
            self.limits = np.array(self.limits, dtype=float).reshape(-1)

    # ---------------------------------------------------------------- the description

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
        if self.limits is not None and check_finite(self, "limits", self.limits, out):
            if self.limits.size != 2:
                out.append(self.problem("limits", f"needs 2 numbers [lower, upper], got "
                                        f"{self.limits.size}"))
            elif not self.limits[0] < self.limits[1]:
                out.append(self.problem("limits", f"the lower limit must be below the upper, "
                                        f"got [{self.limits[0]:g}, {self.limits[1]:g}]"))
        return out

    def scaled(self, length):
        out = super().scaled(length)
        out.parent_frame = scaled_ref(self.parent_frame, length)
        out.child_frame = scaled_ref(self.child_frame, length)
        out.origin = scaled_ref(self.origin, length)
        if self.limits is not None and self.coordinate_unit == LENGTH:
            out.limits = self.limits * length
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

    @classmethod
    def file_keys(cls, dimension: int) -> dict[str, tuple[str, bool]]:
        """The keys a scene file may give for this type beyond the common ones (name, type,
        parent, child, parent_frame, child_frame, origin, rotation), each with the kind of its
        value (:data:`NUMBER`, :data:`VECTOR`, :data:`VECTOR3`, :data:`PAIR`) and whether it
        is required. Each is a field of the class; the writer writes these and no other."""
        return {}

    def unit_axis(self, dimension: int) -> np.ndarray | None:
        """The unit axis in the joint frame (d,), its default when not given; None when the
        type has no axis in ``dimension`` dimensions (a planar revolute joint turns about the
        plane's normal)."""
        if dimension not in self.default_axis:
            return None
        axis = self.axis if self.axis is not None else self.default_axis[dimension]
        return np.asarray(axis, dtype=float) / np.linalg.norm(axis)

    # ---------------------------------------------------------------- the equations

    def rows(self, g: JointGeometry, laws: LawSymbols) -> list[Row]:
        """The constraint rows: ``(name, residual, unit kind)``, the residual a CasADi
        expression of the geometry's body states (zero when the joint holds)."""
        raise NotImplementedError(f"joint type {self.kind!r} writes no rows")

    def driver_row(self, g: JointGeometry, f) -> Any:
        """A driver's residual for the law value ``f`` (drivable types): zero when the
        coordinate equals ``f``, derivative +1 in the coordinate."""
        raise NotImplementedError(f"a {self.kind} joint has no coordinate to drive")

    def rate(self, g: JointGeometry, q, qdot) -> Any:
        """The coordinate's rate along ``q_dot`` (drivable types): the power-conjugate of an
        effort on the joint, so that the effort's power is ``effort * rate``."""
        raise NotImplementedError(f"a {self.kind} joint has no coordinate")

    def twist(self, dimension: int) -> tuple[np.ndarray, np.ndarray] | None:
        """The child's motion relative to the parent per unit coordinate rate: the velocity of
        the joint origin and the angular velocity, (3,) each, in the joint frame (a planar
        vector embedded with zero z, a planar rotation about z); None for types without a
        coordinate."""
        return None

    def effort(self, force: np.ndarray, torque: np.ndarray, dimension: int) -> np.ndarray:
        """The effort along the coordinate of a wrench: ``force`` (N) and ``torque`` (N m, about
        the joint origin), arrays (..., 3) in the joint frame, dotted with :meth:`twist`; NaN
        (shape (...)) for types without a coordinate."""
        twist = self.twist(dimension)
        if twist is None:
            return np.full(np.shape(force)[:-1], np.nan)
        parts = [x @ d for x, d in zip((force, torque), twist, strict=True) if np.any(d)]
        return parts[0] if len(parts) == 1 else parts[0] + parts[1]

    def _axis_twist(self, dimension: int, linear: float, angular: float):
        """``(linear a, angular a)`` for the unit axis ``a`` (the plane's normal when the type
        has no axis in the plane); shared by the types that move along or about their axis."""
        axis = self.unit_axis(dimension)
        a = np.array([0.0, 0.0, 1.0]) if axis is None else embedded(axis)
        return linear * a, angular * a


# ------------------------------------------------------------------ the registry

#: Joint classes by the ``type`` used in scene files, in the order messages list them.
JOINT_TYPES: dict[str, type[Joint]] = {}


def register(cls: type[Joint]) -> type[Joint]:
    """Add a joint type to :data:`JOINT_TYPES` under its ``kind`` (a class decorator).
    Registering a class of the same module and name again replaces it.

    Raises
    ------
    TypeError
        ``cls`` is not a subclass of :class:`Joint`.
    ValueError
        Its ``kind`` is empty or taken by another class.
    """
    if not (isinstance(cls, type) and issubclass(cls, Joint)):
        raise TypeError(f"a joint type must be a subclass of Joint, got {cls!r}")
    kind = cls.kind
    if not isinstance(kind, str) or not kind:
        raise ValueError(f"joint type {cls.__qualname__} has no kind (its name in scene files)")
    known = JOINT_TYPES.get(kind)
    if known is not None and (known.__module__, known.__qualname__) != (
            cls.__module__, cls.__qualname__):
        raise ValueError(f"joint type '{kind}' is taken by {known.__module__}."
                         f"{known.__qualname__}")
    JOINT_TYPES[kind] = cls
    return cls


def unregister(kind: str) -> None:
    """Remove the joint type ``kind`` from :data:`JOINT_TYPES` (a test's own type, after it)."""
    JOINT_TYPES.pop(kind, None)


def kinds_that(question: Callable[[type[Joint]], bool]) -> str:
    """The registered types for which ``question`` holds, as a message lists them:
    ``"revolute and prismatic"``."""
    kinds = [kind for kind, cls in JOINT_TYPES.items() if question(cls)]
    return ", ".join(kinds[:-1]) + " and " + kinds[-1] if len(kinds) > 1 else "".join(kinds)
