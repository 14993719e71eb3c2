"""What a model knows of each of its elements: frozen records of bodies, joints, contacts,
drivers, force elements and constraint rows, with their slices of the coordinate vectors and
their rows (the index maps of :class:`hexapod.model.model.Model`), and the symbols its
Functions are built from (:class:`Symbolic`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from hexapod.scene.joints import Joint
from hexapod.scene.laws import Law
from hexapod.spatial import Placement

if TYPE_CHECKING:
    import casadi as ca

#: The body index of the ground.
GROUND_INDEX = -1


@dataclass(frozen=True)
class BodyInfo:
    """One body of the model. ``q`` and ``v`` are its slices of the coordinate vectors."""

    name: str
    kind: str  # "spatial" | "planar" | "particle"
    index: int
    q: slice
    v: slice
    mass: float
    inertia: np.ndarray  # about the centre of mass, body axes: 3 x 3, 1 x 1 (plane), 0 x 0
    com: np.ndarray  # centre of mass in the body's reference frame (for reference-frame poses)
    markers: dict[str, Placement] = field(default_factory=dict)  # in the centre-of-mass frame


@dataclass(frozen=True)
class JointInfo:
    """One joint. Frames are given in the centre-of-mass frames of the bodies (world: ground).

    ``type`` is the joint itself, in SI units (the copy of the scene :meth:`Scene.in_si` made
    for the assembly, which nothing changes), and answers the algorithms' questions about its
    type (whether it is ``drivable``, its ``twist`` and ``effort``, its ``tree_step``, its
    ``effort_unit``: :class:`hexapod.scene.joints.Joint`); ``kind`` is its type's name.
    """

    name: str
    kind: str
    index: int
    parent: int  # body index, GROUND_INDEX for the ground
    child: int
    parent_frame: Placement
    child_frame: Placement
    axis: np.ndarray | None  # unit, in the joint frame (the type's unit_axis)
    rows: np.ndarray  # the joint's own constraint rows
    driver_rows: np.ndarray  # rows of the drivers acting on this joint
    loop_closing: bool
    type: Joint
    across: tuple[str, ...] = ()  # force elements acting across the joint
    across_column: int = -1  # column of Q_across holding them, -1 when none
    #: the shift of the frame's origin on the child (SX of the laws ``w``, child axes) where a
    #: design parameter moves it (``assemble(moved_frames=...)``), None otherwise
    child_shift: object = None


@dataclass(frozen=True)
class ContactInfo:
    """A foot contact: its joint (index into ``Model.joints``), its three rows (world x, y,
    z of ``gate (r_foot - foothold)``), its schedule (the scene's
    :class:`~hexapod.scene.joints.Contact`, in SI) and the index of its gate in the law
    values ``w`` (1 in stance, 0 in swing)."""

    name: str
    joint: int
    rows: np.ndarray
    schedule: object
    gate: int

    def in_stance(self, t) -> np.ndarray:
        """Whether the foot is on the ground at ``t`` (touch-down included)."""
        from hexapod.scene.contacts import in_stance

        return in_stance(self.schedule, t)

    def weight(self, t) -> np.ndarray:
        """The foot's weight in the ground-force policy at ``t``
        (:func:`hexapod.scene.contacts.stance_weight`)."""
        from hexapod.scene.contacts import stance_weight

        return stance_weight(self.schedule, t)

    def weight_rate(self, t, key: str) -> np.ndarray:
        """The derivative of :meth:`weight` with respect to the design parameter ``key``
        (``gait.duty``: :func:`hexapod.scene.contacts.stance_weight_rate`; zero for
        another)."""
        from hexapod.scene.contacts import stance_weight_rate

        if key == "gait.duty":
            return stance_weight_rate(self.schedule, t)
        return np.zeros_like(np.asarray(t, dtype=float))

    def stances(self, start: float, stop: float) -> list[tuple[float, float]]:
        """The stances (touch-down to lift-off) overlapping ``[start, stop]``, clipped to it."""
        from hexapod.scene.contacts import stance_intervals

        return stance_intervals(self.schedule, start, stop)


class ContactSchedules:
    """The schedules of a model's contacts together: whether each foot is down at a time and
    its weight, all feet in one pass (:func:`hexapod.scene.contacts.schedule_arrays`: the same
    arithmetic as :meth:`ContactInfo.in_stance` and :meth:`ContactInfo.weight`, each)."""

    def __init__(self, contacts):
        from hexapod.scene.contacts import schedule_arrays

        self._arrays = schedule_arrays([c.schedule for c in contacts])

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """``(stance, weight)`` at ``t``: booleans and weights, one per contact."""
        from hexapod.scene.contacts import in_stance, stance_weight

        return in_stance(self._arrays, t), stance_weight(self._arrays, t)


@dataclass(frozen=True)
class DriverInfo:
    """One driver row. ``joint`` for joint drivers; ``body``, ``coordinate`` and ``frame`` (the
    body whose axes measure it, ``GROUND_INDEX`` for the world) otherwise."""

    name: str
    kind: str  # "joint" | "coordinate"
    row: int
    law: int  # index into Model.laws, -1 for a constant law (folded into the row)
    spec: Law | None = None  # the law itself, for descriptions
    joint: int | None = None
    body: int | None = None
    coordinate: str | None = None
    frame: int = GROUND_INDEX


@dataclass(frozen=True)
class SurfaceContact:
    """The plane and the laws of a unilateral contact (a ``ground-contact`` force element):
    its force is decided by a contact scheme, not by the state."""

    surface_point: np.ndarray  # a point of the plane, world (m)
    normal: np.ndarray  # unit, world, out of the ground
    tangents: np.ndarray  # (dimension - 1, dimension): unit, orthogonal, world
    restitution: float
    mu: float
    armed_ahead_of: str | None = None  # another contact: armed while ahead of it
    forward: np.ndarray | None = None  # unit, world: what "ahead" means

    @classmethod
    def plane(cls, surface_point: np.ndarray, normal: np.ndarray, restitution: float,
              mu: float, armed_ahead_of: str | None = None,
              forward: np.ndarray | None = None) -> SurfaceContact:
        """The contact of a plane through ``surface_point`` with unit ``normal``, with tangent
        axes: in space the world axis farthest from the normal, made orthogonal to it, and
        ``normal x t1``; in the plane the normal turned by -90 degrees."""
        n = np.asarray(normal, dtype=float)
        if n.size == 2:
            tangents = np.array([[n[1], -n[0]]])
        else:
            axis = np.eye(3)[int(np.argmin(np.abs(n)))]
            t1 = axis - (axis @ n) * n
            t1 /= np.linalg.norm(t1)
            tangents = np.array([t1, np.cross(n, t1)])
        if armed_ahead_of is not None:
            forward = tangents[0] if forward is None else np.asarray(forward, dtype=float)
            forward = forward / np.linalg.norm(forward)
        return cls(np.asarray(surface_point, dtype=float), n, tangents, float(restitution),
                   float(mu), armed_ahead_of, forward if armed_ahead_of is not None else None)


@dataclass(frozen=True)
class ForceInfo:
    """One force element: the bodies it acts on and where (points in the bodies'
    centre-of-mass frames, world on the ground; none for torques), or the joint it acts across."""

    name: str
    kind: str  # "spring", "applied-force", "applied-torque", "effort", "rotational-spring",
    #            "ground-contact"
    bodies: tuple[int, ...]
    points: tuple[np.ndarray, ...] = ()
    joint: int | None = None
    contact: SurfaceContact | None = None  # a ground contact's plane and laws


@dataclass(frozen=True)
class RowInfo:
    """One constraint row: its name (``joint/row`` or the driver's name), owner and unit kind."""

    name: str
    owner: str
    kind: str  # "length" | "angle"


@dataclass
class Symbolic:
    """The CasADi symbols and expressions a model's Functions are built from."""

    q: ca.SX
    v: ca.SX
    w: ca.SX
    wd: ca.SX
    wdd: ca.SX
    qdot: ca.SX  # B(q) v
    phi: ca.SX
    Q: ca.SX
    Q_across: ca.SX | None = None  # n_v x (joints with force elements across them)
    potential: ca.SX | None = None  # potential energy of gravity and springs (scalar)
    tracking: ca.SX | None = None  # each joint controller's coordinate minus its target
    guided: ca.SX | None = None  # the coordinates of the joints that follow the guides
    ranged: ca.SX | None = None  # the coordinates of the joints with a range, in joint order
    #: the characteristic length as an expression of the laws where design parameters move
    #: the joint points it is measured on (``assemble(moved_frames=...)``); else the number
    length: ca.SX | None = None
    #: what every length is multiplied by where a design parameter scales the model
    #: (``assemble(scaled=...)``: ``1 + sigma``), else None
    scale: ca.SX | None = None


@dataclass(frozen=True)
class Guidance:
    """How a model's guided joints move: ``kinematics`` is the model of the same scene with the
    guides as drivers and the guided joints free, whose motion gives the joints' coordinates
    (``Symbolic.guided``, in order) that the laws ``laws`` (indices into ``Model.laws``) take."""

    kinematics: object  # Model (defined above this module's users)
    laws: np.ndarray
